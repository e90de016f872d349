"""The paper's studies, one module each, with a registry and the ``study`` command::

    dryfriction study list
    dryfriction study <name> [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
                             [--set key=value ...] [--config FILE] [--fmu PATH]
    python -m dryfriction.studies <name> ...

Each study reads ``configs/<name>.toml`` (see :mod:`dryfriction.studies.config`), writes its
NetCDF dataset(s), PNG figure(s), the effective ``config.toml`` and ``summary.json`` into a staging
folder and moves them into ``<out>/<name>/`` (default ``results/<name>/``) together when all are
written (:func:`run_study`). Sweeps keep their finished chunks in ``<out>/<name>/chunks/``, checked
when loaded: a killed sweep started again loads them and computes only the rest.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from . import (fig2_validation, fig3_frequency_response, fig4_steady_cycles, fig5_6_resonance, fig7_stiction,
               fig8_9_bifurcation, fig10_11_frequency_chi, fig12_14_subharmonic)
from .. import paths
from ..cli.options import add_max_work_argument, make_parser, path_arg
from ..atomic import atomic_write_text
from ..budget import Estimate
from .config import ConfigError, build_config, config_dir, load_toml

__all__ = ["STUDIES", "ALIASES", "main", "run_args", "add_arguments", "run_study", "resolve", "effective_config",
           "StudyOutcome", "dump_toml", "study_work", "check_study"]

#: name -> module (NAME, TITLE, FIGURES, check(cfg), work(cfg) -> Estimate, run(ctx) -> summary)
STUDIES: dict[str, ModuleType] = {m.NAME: m for m in (
    fig2_validation, fig3_frequency_response, fig4_steady_cycles, fig5_6_resonance, fig7_stiction,
    fig8_9_bifurcation, fig10_11_frequency_chi, fig12_14_subharmonic)}

from . import chaos_basins, chaos_scan, chaos_transients  # noqa: E402
STUDIES.update({m.NAME: m for m in (chaos_scan, chaos_basins, chaos_transients)})

from . import burridge_knopoff, chain2, chain_waves  # noqa: E402
STUDIES.update({m.NAME: m for m in (chain2, chain_waves, burridge_knopoff)})

from . import fig8_9_orbits, fig10_11_orbits  # noqa: E402
STUDIES.update({m.NAME: m for m in (fig8_9_orbits, fig10_11_orbits)})

from . import belt_map  # noqa: E402
STUDIES.update({belt_map.NAME: belt_map})

ALIASES = {"fig5": "fig5_6", "fig6": "fig5_6", "fig8": "fig8_9", "fig9": "fig8_9", "fig10": "fig10_11",
           "fig11": "fig10_11", "fig12": "fig12_14", "fig13": "fig12_14", "fig14": "fig12_14"}

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 3



def resolve(name: str) -> str:
    """The study's name for ``name`` (case, dashes and aliases such as ``fig5`` allowed); ConfigError naming
    the studies otherwise."""
    key = name.strip().lower().replace("-", "_")
    key = ALIASES.get(key, key)
    if key not in STUDIES:
        raise ConfigError(f"unknown study {name!r}; the studies are: {', '.join(STUDIES)} (or 'list', 'all')")
    return key


def effective_config(name: str, quick: bool = False, config_file: str | os.PathLike[str] | None = None,
                     sets: Sequence[str] = ()) -> dict[str, Any]:
    """The checked configuration of a study (ConfigError if invalid)."""
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
    from ..atomic import staged_outputs
    from ..sweep.engine import EngineOptions, prune_stale
    from .common import StudyContext

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


# ---- command line -----------------------------------------------------------------------------

def add_arguments(p: argparse.ArgumentParser, fmu: bool = True) -> argparse.ArgumentParser:
    """The study command's arguments (``fmu=False``: the caller's parser has a global ``--fmu``)."""
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    width = max(map(len, STUDIES))
    p.epilog = "studies:\n" + "\n".join(f"  {n:{width}s}  {m.TITLE}" for n, m in STUDIES.items())
    p.add_argument("name", help="study name (fig2, fig3, ..., or list, all)")
    p.add_argument("--quick", action="store_true", help="small sizes (CI): the config's [quick] table")
    p.add_argument("--out", type=path_arg("--out"), default="results", metavar="DIR",
                   help="results root; files go to DIR/<study>/")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="Dask LocalCluster worker processes (default: all cores; 0: no Dask, this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDR",
                   help="address of an existing Dask scheduler (tcp://host:8786) instead of a LocalCluster")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                   help="override a config value, e.g. --set sweep.chi.num=20 (repeatable)")
    p.add_argument("--config", default=None, metavar="FILE", help="TOML file overriding the study's config")
    if fmu:
        p.add_argument("--fmu", default=None, metavar="PATH",
                       help="the FMU (default: $DFO_FMU, else the installed package's, else build/)")
    p.add_argument("--max-chunks", type=int, default=None, metavar="N",
                   help="stop after computing N new chunks (exit 3; run again to finish)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    if fmu:  # else the caller's parser has the global --max-work
        add_max_work_argument(p)
    p.add_argument("--show-config", action="store_true", help="print the effective config and exit")
    return p


def _parser(prog: str) -> argparse.ArgumentParser:
    return add_arguments(make_parser(prog, "Reproduce a study of the paper (see 'list')."))


def _list() -> str:
    """The studies as a table, its columns as wide as their longest entry."""
    rows = [("study", "figures", "title")] + [(n, ", ".join(m.FIGURES), m.TITLE) for n, m in STUDIES.items()]
    w0, w1 = (max(len(r[i]) for r in rows) for i in (0, 1))
    lines = [f"{a:{w0}s}  {b:{w1}s}  {c}" for a, b, c in rows]
    lines.append("aliases: " + ", ".join(f"{a} -> {b}" for a, b in ALIASES.items()))
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None, prog: str = "dryfriction study") -> int:
    """``study <name> [options]``; returns the exit status (0 ok, 1 failed, 2 bad input or an error
    the FMU reports, 3 stopped, 130 interrupted). Errors are one line ``dryfriction: error: ...``
    (:func:`dryfriction.cli.console.guarded`), as from ``dryfriction study``."""
    from ..cli.console import guarded

    args_list = list(sys.argv[1:] if argv is None else argv)
    if args_list and args_list[0] in ("-h", "--help"):
        _parser(prog).print_help()
        return EXIT_OK

    def command() -> int:
        try:
            args = _parser(prog).parse_args(args_list)
        except SystemExit as e:  # --help anywhere
            return int(e.code or 0)
        return run_args(args, prog)

    return guarded(command)


def run_args(args: argparse.Namespace, prog: str = "dryfriction study") -> int:
    """Run the study command of parsed arguments (see :func:`add_arguments`); ``prog`` names the
    command in its help only. Bad input raises UsageError (one line, exit 2, reported by the
    caller: :func:`main`, ``dryfriction study``); an interrupt is KeyboardInterrupt (finished
    chunks are kept)."""
    from ..cli.console import PREFIX
    from ..atomic import interrupt_note, interrupted
    from ..errors import FMUError
    from ..sweep.engine import SweepInterrupted

    try:
        if args.name == "list":
            print(_list())
            return EXIT_OK
        names = list(STUDIES) if args.name == "all" else [resolve(args.name)]
        if args.name == "all" and (args.sets or args.config):
            raise ConfigError("--set and --config apply to one study, not to 'all'")
        # check every study's config before any work starts
        cfgs = {n: effective_config(n, args.quick, args.config, args.sets) for n in names}
        if args.show_config:
            for n, cfg in cfgs.items():
                print(dump_toml(cfg, header=f"study {n}" + (" (--quick)" if args.quick else "")))
            return EXIT_OK
        # every study's work and output checked before the first starts
        total = 0.0
        for n, cfg in cfgs.items():
            total += check_study(n, cfg, Path(args.out) / n, getattr(args, "max_work", None)).out_bytes
        if len(names) > 1:
            from ..budget import check_writable

            check_writable(args.out, OUTPUT_MARGIN * total, "the results and chunks of all studies")
        fmu = getattr(args, "fmu", None)
        interrupt_note("finished chunks are kept, run again to resume")
        for n in names:
            print(f"== study {n}: {STUDIES[n].TITLE}", flush=True)
            run_study(n, quick=args.quick, out=args.out, workers=args.workers, scheduler=args.scheduler,
                      sets=args.sets, config_file=args.config, fmu=fmu, max_chunks=args.max_chunks,
                      progress=not args.no_progress, max_work=getattr(args, "max_work", None))
        return EXIT_OK
    except SweepInterrupted as e:
        print(f"{PREFIX}: {e}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except RuntimeError as e:
        if interrupted() or isinstance(e, FMUError):  # said by the caller: the interrupt, exit 2
            raise
        print(f"{PREFIX}: error: {e}", file=sys.stderr)
        return EXIT_FAILED
