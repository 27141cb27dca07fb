"""The material laws' ids, as the kernels branch on them (``catenet.kernels.laws.density``)
and as ``catenet.model.laws`` names them for users: plain constants, no Numba."""

LINEAR = 0
NEO_HOOKEAN = 1
HENCKY = 2
TABLE = 3
