"""The paper's studies and the project's own, one module each, and their registry::

    dryfriction study list                   # the command (dryfriction.cli.study)
    dryfriction study <name> [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
                             [--set key=value ...] [--config FILE] [--fmu PATH]
    python -m dryfriction.studies <name> ...  # the same
    run_study("fig3", quick=True)            # the Python API

:data:`REGISTRY` names every study, its module, title and figures; a study's module (and what it
imports: NumPy, xarray, matplotlib, Dask) is imported only when the study runs or is asked for by
name (:data:`STUDIES`), so that importing this package, listing the studies and the command's help
are immediate.

Each study reads ``configs/<name>.toml`` (see :mod:`dryfriction.studies.config`), writes its
NetCDF dataset(s), PNG figure(s), the effective ``config.toml`` and ``summary.json`` into a staging
folder and moves them into ``<out>/<name>/`` (default ``results/<name>/``) together when all are
written (:func:`run_study`). Sweeps keep their finished chunks in ``<out>/<name>/chunks/``, checked
when loaded: a killed sweep started again loads them and computes only the rest.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from importlib import import_module
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..budget import Estimate

__all__ = ["REGISTRY", "Study", "STUDIES", "ALIASES", "run_study", "resolve", "effective_config", "StudyOutcome",
           "dump_toml", "study_work", "check_study", "OUTPUT_MARGIN"]


@dataclass(frozen=True)
class Study:
    """A study in the registry: its module in this package (which defines ``check(cfg)``,
    ``work(cfg) -> Estimate`` and ``run(ctx) -> summary``; its ``TITLE`` and ``FIGURES`` are these),
    the figures it draws and its title."""

    module: str
    figures: tuple[str, ...]
    title: str


#: study name -> :class:`Study`, in the order ``study list`` and ``study all`` take them
REGISTRY: dict[str, Study] = {
    "fig2": Study("fig2_validation", ("fig2.png",),
              "FMU vs exact solution over the first cycle (z, z', z'')"),
    "fig3": Study("fig3_frequency_response", ("fig3.png",),
              "Steady-state frequency response from rest vs Inman and Den Hartog"),
    "fig4": Study("fig4_steady_cycles", ("fig4.png",),
              "Four steady-state cycles below and above resonance"),
    "fig5_6": Study("fig5_6_resonance", ("fig5.png", "fig6.png"),
                "Unbounded growth at resonance (4 mu_k N < pi P0) and beating near it"),
    "fig7": Study("fig7_stiction", ("fig7.png",),
              "Percentage stiction time in the 30th cycle vs frequency ratio, ten friction levels"),
    "fig8_9": Study("fig8_9_bifurcation", ("fig8.png", "fig9.png"),
                "Mean amplitude and asymmetry vs chi over a grid of initial conditions (bifurcation)"),
    "fig10_11": Study("fig10_11_frequency_chi", ("fig10.png", "fig11.png"),
                  "Frequency-response curves for several chi over a grid of initial conditions"),
    "fig12_14": Study("fig12_14_subharmonic", ("fig12.png", "fig13.png", "fig14.png"),
                  "Time histories, phase portraits and diverging nearby initial conditions (sub-harmonic zone)"),
    "chaos_scan": Study("chaos_scan", ("chaos_bifurcation.png", "chaos_section.png"),
                    "Largest Lyapunov exponent and bifurcation diagram vs chi (Fig. 8/9 range); onset of chaos"),
    "chaos_basins": Study("chaos_basins", ("chaos_basins_<case>.png",),
                      "Basins of attraction where motions coexist (end of the chaotic range of Fig. 8/9; Fig. 11 zone)"),
    "chaos_transients": Study("chaos_transients", ("chaos_transients.png",),
                          "Transient or permanent: spread after 30/300/1000 periods, transient lengths (Fig. 8/9 range)"),
    "chain2": Study("chain2", ("chain2.png",),
                "Chain of two blocks, the first forced: amplitude and stick share against frequency (friction on both / second)"),
    "chain_waves": Study("chain_waves", ("chain_waves.png",),
                     "Stick-slip fronts along a chain of 256 blocks, the first forced: space-time image of the modes"),
    "burridge_knopoff": Study("burridge_knopoff", ("burridge_knopoff.png",),
                          "Burridge-Knopoff fault model (Carlson-Langer): slip events, their moments, the power law"),
    "fig8_9_orbits": Study("fig8_9_orbits", ("fig8_9_orbits.png",),
                       "Fig. 8/9 band: branches of periodic orbits in chi over the scatter, bifurcations vs brute force"),
    "fig10_11_orbits": Study("fig10_11_orbits", ("fig10_orbits.png", "fig11_orbits.png"),
                         "Fig. 10/11 as branches of periodic orbits in lambda with stability, over the scatter"),
    "belt_map": Study("belt_map", ("belt_map.png",),
                  "Self-excited stick-slip over belt speed x normal force, with the Hopf line"),
}


class _Modules(Mapping[str, ModuleType]):
    """Study name -> its module, imported when first asked for."""

    def __getitem__(self, name: str) -> ModuleType:
        return import_module(f"{__name__}.{REGISTRY[name].module}")

    def __iter__(self) -> Iterator[str]:
        return iter(REGISTRY)

    def __len__(self) -> int:
        return len(REGISTRY)


#: study name -> its module (imported on first access: ``STUDIES["fig3"]``); the names alone
#: (``list(STUDIES)``, ``name in STUDIES``) import nothing
STUDIES: Mapping[str, ModuleType] = _Modules()

ALIASES = {"fig5": "fig5_6", "fig6": "fig5_6", "fig8": "fig8_9", "fig9": "fig8_9", "fig10": "fig10_11",
           "fig11": "fig10_11", "fig12": "fig12_14", "fig13": "fig12_14", "fig14": "fig12_14"}



def resolve(name: str) -> str:
    """The registry's name of the study ``name`` (an alias, any case, ``-`` for ``_``); ConfigError
    (one line listing the studies) for a name that is none."""
    from .config import ConfigError

    key = name.strip().lower().replace("-", "_")
    key = ALIASES.get(key, key)
    if key not in REGISTRY:
        raise ConfigError(f"unknown study {name!r}; the studies are: {', '.join(STUDIES)} (or 'list', 'all')")
    return key


def effective_config(name: str, quick: bool = False, config_file: str | os.PathLike[str] | None = None,
                     sets: Sequence[str] = ()) -> dict[str, Any]:
    """The checked configuration of a study (ConfigError if invalid)."""
    from .config import ConfigError, build_config

    default = _default_config(name)
    cfg = build_config(default, quick=quick, config_file=config_file, sets=sets)
    try:
        STUDIES[name].check(cfg)
    except KeyError as e:
        raise ConfigError(f"configs/{name}.toml lacks the key {e.args[0]!r}") from None
    return cfg


def _default_config(name: str) -> dict[str, Any]:
    """``configs/<name>.toml``; a study with ``BASE_CONFIG`` (it draws over another study's sweep)
    gets that study's file with its own tables added on top (their ``[quick]`` tables merged too),
    so the values of the shared sweep are written once."""
    from .config import config_dir, load_toml

    own = load_toml(config_dir() / f"{name}.toml")
    base = getattr(STUDIES[name], "BASE_CONFIG", None)
    if base is None:
        return own
    cfg = load_toml(config_dir() / f"{base}.toml")

    def update(into: dict[str, Any], new: dict[str, Any]) -> None:
        for k, v in new.items():
            if isinstance(v, dict) and isinstance(into.get(k), dict):
                update(into[k], v)
            else:
                into[k] = v

    update(cfg, own)
    return cfg


@dataclass
class StudyOutcome:
    """What :func:`run_study` returns: the study's name, its output folder, its summary, the sweeps'
    statistics and the messages it printed."""
    name: str
    out_dir: Path
    summary: dict[str, Any]
    stats: list[Any]
    messages: list[str]


def run_study(name: str, *, quick: bool = False, out: str | os.PathLike[str] = "results", workers: int | None = None,
              scheduler: str | None = None, sets: Sequence[str] = (), config_file: str | os.PathLike[str] | None = None,
              fmu: str | os.PathLike[str] | None = None, max_chunks: int | None = None,
              progress: bool = True, max_work: float | None = None) -> StudyOutcome:
    """Run one study (Python API of ``dryfriction study``). Raises ConfigError before any work if
    an argument or config value is invalid or the output folder cannot be written,
    :class:`~dryfriction.budget.WorkBoundError` before any work if the study's estimated total work
    (every sweep, batch and trajectory it runs: :func:`study_work`) exceeds ``max_work`` (steps,
    :mod:`dryfriction.budget`), SweepInterrupted if ``max_chunks`` stopped a sweep.

    The results (datasets, figures), ``config.toml`` and ``summary.json`` are written into a staging
    folder and moved into ``<out>/<study>/`` together once all are written
    (:func:`dryfriction.atomic.staged_outputs`): a failed or interrupted run leaves the previous
    results and their configuration as they were. A folder holding another configuration's results
    is started clean (a note says so): they are replaced when this run's are complete, and the
    chunks of the previous configuration are removed only then."""
    from .. import paths
    from ..atomic import staged_outputs
    from ..sweep.engine import EngineOptions, prune_stale
    from .common import StudyContext
    from .config import ConfigError

    key = resolve(name)
    cfg = effective_config(key, quick=quick, config_file=config_file, sets=sets)
    # the FMU (checked: paths.FMUFileError, a UsageError); a study of another model (the chain)
    # names its kind: module.FMU_KIND
    fmu_path = paths.fmu_path(getattr(STUDIES[key], "FMU_KIND", paths.OSCILLATOR), fmu)
    n_workers = (os.cpu_count() or 1) if workers is None else workers
    if n_workers < 0:
        raise ConfigError(f"--workers must be >= 0, not {n_workers}")
    if max_chunks is not None and max_chunks < 0:
        raise ConfigError(f"--max-chunks must be >= 0, not {max_chunks}")
    out_dir = Path(out) / key
    # found before the work: more work than --max-work, a folder that cannot take a file, a disk
    # without room for the results and chunks
    check_study(key, cfg, out_dir, max_work)
    config_text = dump_toml(cfg, header=f"effective configuration of study {key}" + (" (--quick)" if quick else ""))
    previous = _previous_config(out_dir)
    if previous is not None and previous != cfg:
        print(f"note: {out_dir} holds the results of another configuration; this run starts clean and "
              "replaces them (with their config.toml) when its results are complete", file=sys.stderr, flush=True)

    opts = EngineOptions(fmu=fmu_path, workers=n_workers, scheduler=scheduler, progress=progress,
                         max_chunks=max_chunks, max_work=max_work)
    with staged_outputs(out_dir) as stage:
        ctx = StudyContext(name=key, cfg=cfg, quick=quick, out_dir=stage, engine_options=opts, final_dir=out_dir)
        folders: set[Path] = set()
        try:
            summary = STUDIES[key].run(ctx)
        finally:
            stats = list(ctx._engine.stats) if ctx._engine is not None else []
            folders = set(ctx._engine.folders) if ctx._engine is not None else set()
            ctx.close()
        record = {"study": key, "quick": quick, "summary": summary,
                  "sweeps": [s.__dict__ for s in stats]}
        _write(stage / "summary.json", json.dumps(record, indent=2, default=float) + "\n")
        _write(stage / "config.toml", config_text)
        new_files = {p.relative_to(stage) for p in stage.rglob("*") if p.is_file()}
    # in place: the previous configuration's files that this run did not write, and its chunks, go
    if previous is not None and previous != cfg:
        for p in out_dir.iterdir():
            if p.is_file() and p.suffix in (".nc", ".png", ".json", ".csv") and Path(p.name) not in new_files:
                p.unlink(missing_ok=True)
    prune_stale(ctx.chunk_dir, folders)
    return StudyOutcome(key, out_dir, summary, stats, ctx.messages)


def study_work(name: str, cfg: dict[str, Any]) -> Estimate:
    """What the study ``name`` will do with the configuration ``cfg``: its work in steps, part by
    part (every sweep, batch and trajectory), and the bytes of its results and chunks
    (:class:`~dryfriction.budget.Estimate`), from the configuration alone."""
    return STUDIES[name].work(cfg)


def check_study(name: str, cfg: dict[str, Any], out_dir: str | os.PathLike[str],
                max_work: float | None = None) -> Estimate:
    """Before any work: refuse (:class:`~dryfriction.budget.WorkBoundError`, one line naming
    ``--max-work`` and the estimate) a study whose total work exceeds ``max_work`` or whose memory
    exceeds half this machine's (naming ``--set``), and (a :class:`UsageError`) an output folder
    that cannot take a file or lacks room for the estimated results and chunks (twice the estimate,
    :data:`OUTPUT_MARGIN`). Returns the estimate."""
    from ..budget import check_writable, max_work_value

    max_work_value(max_work)
    est = study_work(name, cfg)
    est.check(f"study {name}", max_work)
    check_writable(out_dir, OUTPUT_MARGIN * est.out_bytes, f"the results and chunks of study {name}")
    return est


#: the free space asked for, over a study's estimated output (results and chunks)
OUTPUT_MARGIN = 2.0


def _write(path: Path, text: str) -> None:
    """A result file; a failure (a full disk) is one line naming the file and the cause."""
    from ..atomic import atomic_write_text

    try:
        atomic_write_text(path, text)
    except OSError as e:
        raise OSError(f"cannot write {path.name}: {e.strerror or e}") from None


def _previous_config(out_dir: Path) -> dict[str, Any] | None:
    """The configuration of the results in ``out_dir`` (its config.toml), None if there are none;
    an unreadable one counts as another configuration."""
    import tomllib

    path = out_dir / "config.toml"
    if not path.is_file():
        return None
    try:
        return tomllib.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def dump_toml(cfg: dict[str, Any], header: str = "") -> str:
    """TOML text of a configuration (``tomli_w``), with a comment line on top."""
    import tomli_w

    text = tomli_w.dumps(cfg)
    return (f"# {header}\n" if header else "") + text
