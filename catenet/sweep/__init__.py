"""Parameter sweeps: a base case run over the Cartesian product of parameter values.

A sweep is a base case file and a list of parameters ``key.path = v1, v2, ...``. Keys under
``load.`` are *load keys*: for every combination of the other keys (a *job*) the load
levels (the product of the load keys' values, in the order given) are solved as one
continuation over one net and one Workspace, each level starting from the previous
equilibrium, so a whole force-displacement curve costs little more than its last point.

Jobs run in this process (``workers=1``), in a pool of spawned processes
(``concurrent.futures.ProcessPoolExecutor``; MKL, OpenMP and Numba threads per process set
to ``max(1, cores // workers)``), or on a Dask distributed cluster (``scheduler=ADDRESS``).

Everything a sweep has found is in the append-only journal ``DIR/results.jsonl``: a header
line (the base case, the parameters and their fingerprint), then one line per finished job,
flushed to disk as soon as the job returns. ``DIR/results.csv`` and ``DIR/results.h5`` are
regenerated from it. Running the same sweep into the same directory again skips the jobs
the journal already holds (resume after a crash or Ctrl-C); a journal of another base case
or other parameters is refused.

Columns of the table: the swept keys (by key path, in the order given), then ``delta``
(z-deflection of the scene's probe node, positive down) [m], ``delta_over_L``, ``F_bar``
(|sum of the external nodal forces| / EA, = p L^2 / EA for the square net), ``max_strain``,
``slack_edges`` (tension-only edges shorter than their rest length), the run summary's
numbers (``catenet.model.summary.COLUMNS``, as ``catenet run`` prints them and writes them
as /result attributes: ``max_displacement`` [m] and its node, ``max_tension`` [N] and its
edge, ``max_compression`` [N], ``max_reaction`` [N] and its node, the resultants of the
reactions and contact forces by component [N], ``peak_tension`` [N] and its time,
``peak_displacement`` [m], ``probe``), ``iterations`` (Newton iterations
of that load level), ``wall_time`` [s] (building the net and the workspace counts towards
the first level of a job), ``converged``, ``error`` (empty on success), ``attempts`` (2
when the job was retried after its worker process died) and ``run_file`` (the level's
HDF5 file under ``runs/`` with ``save_runs``, else empty).

Test hook: with ``CATENET_TEST_CRASH=<job index>`` in the environment, a worker process
(pool or Dask, never the calling process) that starts that job exits with status 1 the
first time, leaving a marker file ``DIR/.crash-<index>`` so that the retry succeeds.

Modules, each importing only the ones above it: ``params`` (the value language and
``Param``), ``jobs`` (``Sweep``, ``Job``, ``load_sweep``, validation), ``solve`` (one
job's load levels: ``run_job``), ``journal`` (the journal and the tables), ``workers``
(the process pool and Dask), ``execute`` (``run_sweep``). None imports NumPy at import time.
"""

from __future__ import annotations

from catenet.sweep.execute import SweepSummary, run_sweep
from catenet.sweep.jobs import RESULT_COLUMNS, Job, Sweep, load_sweep, make_sweep, toml_literal
from catenet.sweep.journal import (
    CSV_FILE,
    H5_FILE,
    JOURNAL,
    read_journal,
    read_table,
    write_tables,
)
from catenet.sweep.params import (
    LOAD_PREFIX,
    Param,
    evaluate,
    expand_range,
    parse_param,
    parse_value,
)
from catenet.sweep.solve import CRASH_VARIABLE, RUNS_DIR, run_job
from catenet.sweep.workers import cores, threads_per_worker

__all__ = [
    "CRASH_VARIABLE",
    "CSV_FILE",
    "H5_FILE",
    "JOURNAL",
    "LOAD_PREFIX",
    "RESULT_COLUMNS",
    "RUNS_DIR",
    "Job",
    "Param",
    "Sweep",
    "SweepSummary",
    "cores",
    "evaluate",
    "expand_range",
    "load_sweep",
    "make_sweep",
    "parse_param",
    "parse_value",
    "read_journal",
    "read_table",
    "run_job",
    "run_sweep",
    "threads_per_worker",
    "toml_literal",
    "write_tables",
]
