"""The untuned corpus (tests/corpus.py): every model converges and balances its loads.

Each model is a well-posed structure (supported, stable, prestress in equilibrium with
the given geometry, loads a designer would apply) written from the README alone, at
catenet's default solver settings. So `catenet run` must exit 0, and the converged state
must satisfy global equilibrium: reactions + applied loads + contact forces = 0 (contract
sections 5 and 7).

Tolerance of the balance, TOL = 1e-6 of the force scale (``corpus.check_equilibrium``: the
largest of the three sums and of the reaction and contact fields' norms): Newton stops at a
residual of rtol = 1e-8 (the default) of the load scale per degree of freedom; summing the
free nodes' residuals into one resultant leaves a factor of 100 for their accumulation
(sqrt(N) for N up to 1e4 nodes) and round-off.

The runs go through the command line's entry point (``catenet run``: the README
documents no Python entry point that runs a case file), in two worker processes that
start the interpreter and the JIT cache once each (``corpus.run_in_process``), all of
the module's selected models started by one fixture (so the module belongs on one
worker, as `make test`'s --dist loadfile does): 20 models of each family; those above
3000 edges are marked slow.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor, wait
from concurrent.futures import TimeoutError as Late

import corpus
import h5py
import pytest

pytestmark = pytest.mark.slow  # 120 whole runs: make test, not make test-fast

PER_FAMILY = 20
TOL = 1e-6
TIMEOUT = 300.0  # s: a hang is a failure, not a stuck test session


def _params():
    for family in corpus.FAMILIES:
        for seed in range(PER_FAMILY):
            slow = corpus.generate(seed, family)["edges"] > 3000
            marks = [pytest.mark.slow] if slow else []
            yield pytest.param(family, seed, id=f"{family}-{seed}", marks=marks)


@pytest.fixture(scope="module")
def runs(request, tmp_path_factory):
    """Every selected model of this module, written, then run two at a time."""
    out = tmp_path_factory.mktemp("corpus")
    wanted = [
        (item.callspec.params["family"], item.callspec.params["seed"])
        for item in request.session.items
        if item.module is request.module and hasattr(item, "callspec")
    ]
    pool = ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"))
    futures = {}
    for family, seed in wanted:
        case = corpus.write(corpus.generate(seed, family), out / f"{family}-{seed}.toml")
        result = case.with_suffix(".h5")
        future = pool.submit(corpus.run_in_process, str(case), str(result))
        if not futures:  # the first run alone: it compiles the kernels (a cold cache) that
            wait([future], timeout=TIMEOUT)  # the second worker then reads, not compiles
        futures[family, seed] = (case, result, future)
    yield futures
    for process in list(getattr(pool, "_processes", {}).values()):  # a hung run, if any
        process.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


@pytest.mark.parametrize(("family", "seed"), list(_params()))
def test_model_converges_and_balances(runs, family, seed):
    case, result, future = runs[family, seed]
    try:
        status, stderr = future.result(timeout=TIMEOUT)
    except Late:
        status, stderr = "timeout", f"no answer within {TIMEOUT:g} s"
    command = f"catenet run {case} -o {result}"
    assert status == 0, f"{command} exited {status}:\n{stderr}"
    with h5py.File(result, "r") as f:
        assert bool(f["result"].attrs["converged"]), f"{command}: converged = false"
    imbalance = corpus.check_equilibrium(result)
    assert imbalance <= TOL, f"{command}: global force imbalance {imbalance:.3g} > {TOL:g}"


def test_generation_is_reproducible():
    for seed in range(12):
        first, again = corpus.generate(seed), corpus.generate(seed)
        assert first == again
        assert first["family"] in corpus.FAMILIES and first["scale"] in corpus.SCALES
