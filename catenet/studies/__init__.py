"""Studies that only the benchmarks and the paper's report need, off the import path of
``catenet run``: ``bench`` (the timing and stress studies of ``catenet bench``),
``square_net`` (the paper's Figs. 5-8, the scaling-law fit and the report of ``catenet
plot DIR``) and ``validation`` (the error table of ``catenet validate``). They call the
solvers like any user of the library; nothing in the core imports them.
"""
