"""Shared fixtures: one FMU instance per test session, reused (reset) by every test; the paths of the
four FMUs; the oscillator's FMI 2.0 FMU unzipped and one fmpy instance of it (fmi2_helpers.Inst);
fmpy's reading of both oscillators' model descriptions; the references of the coupled chain cases;
the cache of the slow pure-Python references (refcache.RefCache).
Nothing here looks for an FMU before a fixture asks for one."""

from __future__ import annotations

import shutil
import signal
import tempfile
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from fmpy import extract, read_model_description

from dryfriction.drivers.chain import default_chain_fmu, default_chain_fmu3
from dryfriction.references.chain import solve_chain
from dryfriction.drivers.oscillator3 import default_fmi3_path
from dryfriction.drivers.oscillator import OscillatorFMU2, default_fmu_path
from dryfriction.paths import FMUFileError

from chain_cases import CASES, PERIODS
from fmi2_helpers import Inst
from refcache import RefCache


# The modules that load no FMU and run no C program (the pure-Python references and parsers): their
# tests are marked python_only, which the ASan/UBSan pass of scripts/test.sh deselects (there is
# nothing in them for the sanitizers to check). A test of one that asks for an FMU fixture is an
# error at collection.
PYTHON_ONLY = frozenset({"test_references.py", "test_belt_reference.py", "test_chain_driver.py",
                         "test_packaging_requirements.py", "test_c_layout.py", "test_two_mass_reference.py",
                         "test_layout.py", "test_roots.py",
                         "test_system_structure.py", "test_system_reference.py", "test_refcache.py",
                         "test_system_cases.py"})
FMU_FIXTURES = frozenset({"fmu", "fmu_path", "chain_fmu2", "chain_fmu3", "unzipped", "inst", "md2", "md3"})

# The modules that take longest (their tests' total time in one full run, longest first): collected
# first, the others after them in their usual order. scripts/test.sh hands modules to the xdist
# workers in collection order (--dist loadfile --no-loadscope-reorder), so the long ones start at
# once and the run ends with short ones on both workers, not with one worker alone on a long module.
LONGEST_FIRST = ("test_cli_interrupt.py", "test_packaging_rebuild.py", "test_sweep_faults.py", "test_studies.py",
                 "test_packaging_wheel.py", "test_bench_smoke.py", "test_study_orbits.py", "test_cosim.py",
                 "test_exact_free.py", "test_exact_poly.py", "test_chaos.py", "test_examples.py",
                 "test_system_orbits.py", "test_exact_edges.py", "test_system_validation.py",
                 "test_system_jenkins.py", "test_system_reference.py", "test_model_exchange.py", "test_hazards.py",
                 "test_belt_exact.py", "test_self_excited.py", "test_system_fmu_writer.py", "test_system_fmu.py",
                 "test_chain_physics.py", "test_belt_reference.py", "test_system_steady_reference.py",
                 "test_layout.py", "test_packaging_locate.py", "test_main_job.py")


# ---- the process's signal handling, as each test finds it ----------------------------------------------

#: tests after which SIGINT's handler or the main thread's signal mask was not Python's default (the
#: next test found it so): restored, and listed at the end of the run
_SIGNAL_LEAKS: list[str] = []
_LAST_TEST: list[str] = ["(the session's start)"]


@pytest.fixture(autouse=True)
def _default_signal_handling(request: pytest.FixtureRequest) -> Iterator[None]:
    """Every test starts with Python's default SIGINT handling (KeyboardInterrupt) and SIGINT and
    SIGTERM unblocked in the main thread, as a library caller has them: the command line's tests
    (tests/test_cli_interrupt.py) raise signals in this process. Where the test before left them
    otherwise, they are restored and that test is named in the run's summary."""
    if threading.current_thread() is threading.main_thread():
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, set())
        held = {signal.SIGINT, signal.SIGTERM} & set(mask)
        if signal.getsignal(signal.SIGINT) is not signal.default_int_handler or held:
            _SIGNAL_LEAKS.append(f"{_LAST_TEST[0]}: SIGINT handler {signal.getsignal(signal.SIGINT)!r}, "
                                 f"blocked {sorted(int(s) for s in held)}")
            signal.signal(signal.SIGINT, signal.default_int_handler)
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
            cache = getattr(request.config, "cache", None)
            if cache is not None:  # (for the summary of the run: an xdist worker's own is not shown)
                cache.set(f"dfo/signal-leaks-{_worker(request.config)}", _SIGNAL_LEAKS)
    yield
    _LAST_TEST[0] = request.node.nodeid


def _worker(config: pytest.Config) -> str:
    """This process's xdist worker id ("main" without xdist)."""
    return str(getattr(config, "workerinput", {}).get("workerid", "main"))


_WORKER_IDS = ["main"] + [f"gw{i}" for i in range(256)]


def pytest_sessionstart(session: pytest.Session) -> None:
    """The run's list of signal leaks starts empty (the controlling process's)."""
    cache = getattr(session.config, "cache", None)
    if cache is not None and not hasattr(session.config, "workerinput"):
        for w in _WORKER_IDS:
            if cache.get(f"dfo/signal-leaks-{w}", None):
                cache.set(f"dfo/signal-leaks-{w}", [])


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """The tests that left the signal handling changed (none expected), from every worker."""
    cache = getattr(terminalreporter.config, "cache", None)
    lines = list(_SIGNAL_LEAKS)
    if cache is not None and not hasattr(terminalreporter.config, "workerinput"):
        lines = [line for w in _WORKER_IDS for line in cache.get(f"dfo/signal-leaks-{w}", [])]
    for line in lines:
        terminalreporter.write_line(f"signal handling left changed by {line}")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Marks the tests of the PYTHON_ONLY modules python_only; puts the LONGEST_FIRST modules first
    (each module's tests in their order)."""
    for item in items:
        if item.path.name in PYTHON_ONLY:
            if used := FMU_FIXTURES.intersection(getattr(item, "fixturenames", ())):
                raise pytest.UsageError(f"{item.nodeid}: a python_only module's test uses {sorted(used)}")
            item.add_marker(pytest.mark.python_only)
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


# Every FMU comes from dryfriction.paths: DFO_FMU, DFO_FMU3, DFO_CHAIN_FMU, DFO_CHAIN_FMU3 select
# other builds (the ASan/UBSan one), else the installed package's, else build/.


def _located(find: Callable[[], Path]) -> Path:
    try:
        return find()
    except FMUFileError as e:
        pytest.fail(str(e))


@pytest.fixture(scope="session")
def fmu_path() -> Path:
    return _located(default_fmu_path)


@pytest.fixture(scope="session")
def fmu(fmu_path: Path) -> Iterator[OscillatorFMU2]:
    with OscillatorFMU2(fmu_path) as f:
        yield f


@pytest.fixture(scope="session")
def chain_fmu3() -> Path:
    """The FMI 3.0 chain FMU (DFO_CHAIN_FMU3 selects another build)."""
    return _located(default_chain_fmu3)


@pytest.fixture(scope="session")
def chain_fmu2() -> Path:
    """The FMI 2.0 chain FMU (DFO_CHAIN_FMU selects another build)."""
    return _located(default_chain_fmu)


@pytest.fixture(scope="module")
def unzipped() -> Iterator[tuple[str, object]]:
    """The oscillator's FMI 2.0 FMU unzipped, and its model description (fmpy's)."""
    path = default_fmu_path()
    assert path.is_file(), f"FMU not found: {path} (build it, or set DFO_FMU)"
    md = read_model_description(str(path))
    d = extract(str(path), unzipdir=tempfile.mkdtemp(prefix="dfo-fmi2-"))
    yield d, md
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture
def inst(unzipped: tuple[str, object]) -> Iterator[Inst]:
    """One FMU2Slave instance with counting callbacks; every allocation freed at the end."""
    i = Inst(unzipped)
    yield i
    i.free()
    assert i.cb.allocs == i.cb.frees, f"{i.cb.allocs} allocations, {i.cb.frees} frees"


@pytest.fixture(scope="session")
def refcache(pytestconfig: pytest.Config) -> RefCache:
    """The slow pure-Python references kept in the pytest cache folder between runs (refcache.py: keyed
    by their inputs and the code; computed every time without the cache provider)."""
    cache = getattr(pytestconfig, "cache", None)
    return RefCache(cache.mkdir("dfo-references") if cache is not None else None)


@pytest.fixture(scope="session")
def refs(refcache: RefCache) -> dict:
    """The event-driven references of the coupled chain cases (chain_cases.CASES) over PERIODS periods."""
    return {name: refcache.call(solve_chain, ch, PERIODS * ch.period) for name, ch in CASES.items()}


@pytest.fixture(scope="module")
def md2(fmu_path: Path) -> object:
    """fmpy's reading of the FMI 2.0 oscillator's model description."""
    return read_model_description(str(fmu_path))


@pytest.fixture(scope="module")
def md3() -> object:
    """fmpy's reading of the FMI 3.0 oscillator's model description."""
    return read_model_description(str(_located(default_fmi3_path)))
