"""Result files: the HDF5 layout of contract §5 and an XDMF sidecar for ParaView.

::

    /                   attrs: catenet_version, case (resolved TOML), created, software
                        versions (<name>_version), linear_backend, threads
    /mesh/nodes (N, 3), edges (M, 2), rest_length (M,), EA (M,), fixed (N,), mass (N,)
                        (each node's lumped mass [kg])
    /trajectory/time (T,), x (T, N, 3), v (T, N, 3) (dynamic runs), a (T, N, 3)
                        (newmark runs: the scheme's acceleration state), tension (T, M)
    /result/x (N, 3), tension (M,), reaction (N, 3), v (N, 3) (dynamic runs),
                        a (N, 3) (newmark runs)
    /result             attrs: converged, iterations, residual, steps, wall_time,
                        equilibrium, message, time, delta, delta_over_L, probe, size,
                        max_strain, max_tension, stable (1/0; -1: not checked)
    /xdmf/x/<k>, /xdmf/tension/<k>, /xdmf/v/<k>: frame k of the trajectory, for the XDMF
                        sidecar (virtual datasets: views of /trajectory, no data)
    /history/time (S,), reaction (S, Ns, 3), reaction_nodes (Ns,), contact (S, K, 3),
                        cable_end_tension (S, C, 2): a dynamic run's every step (``history``)
    /mesh/bodies, /mesh/obstacles, /trajectory/obstacles, /result/obstacles,
    /xdmf/obstacles/<k>/vertices/<f>: moving spheres (``bodies``) and the other obstacles'
                        surfaces and moving ones' frames (``obstacles``)

Modules: ``writer`` (``ResultWriter``: the file while a run goes on, crash safety, full
disks), ``files`` (``check_output_path``, the spare copy, atomic publishing),
``metadata`` (software versions, the /result attributes),
``reader`` (``read_result``, ``read_frame``, ``read_mesh``, ``open_result``: the only
code that reads the layout, also of killed runs), ``repair`` (``recover``, ``repair``:
files that need mending), ``bodies`` and ``obstacles`` (moving spheres; the obstacles'
surfaces, ``read_obstacles``), ``history`` (a dynamic run's rows, ``read_history``), ``xdmf`` (the
sidecar and the per-frame views /xdmf/<name>/<k> it names), ``export`` (frames to other
formats through meshio).
"""

from catenet.output.bodies import read_bodies
from catenet.output.files import check_output_path, remove_spares
from catenet.output.history import read_history
from catenet.output.metadata import environment, result_attrs
from catenet.output.obstacles import read_obstacles
from catenet.output.reader import (
    Frame,
    NetMesh,
    ResultFile,
    open_result,
    probe_node,
    read_frame,
    read_mesh,
    read_result,
    trajectory_length,
)
from catenet.output.repair import Repair, recover, repair
from catenet.output.writer import ResultWriter
from catenet.output.xdmf import sidecar_path, write_views, write_xdmf

__all__ = [
    "Frame",
    "NetMesh",
    "Repair",
    "ResultFile",
    "ResultWriter",
    "check_output_path",
    "environment",
    "open_result",
    "probe_node",
    "read_bodies",
    "read_frame",
    "read_history",
    "read_mesh",
    "read_obstacles",
    "read_result",
    "recover",
    "remove_spares",
    "repair",
    "result_attrs",
    "sidecar_path",
    "trajectory_length",
    "write_views",
    "write_xdmf",
]
