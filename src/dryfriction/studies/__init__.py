"""The paper's studies, one module each, with a registry and the ``study`` command.

    dryfriction study list
    dryfriction study <name> [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
                             [--set key=value ...] [--config FILE] [--fmu PATH]
    python -m dryfriction.studies <name> ...

Each study reads ``configs/<name>.toml`` (see :mod:`dryfriction.studies.config`), writes its
NetCDF dataset(s), PNG figure(s), the effective ``config.toml`` and ``summary.json`` to
``<out>/<name>/`` (default ``results/<name>/``), every file through a temp name and a rename.
Sweeps keep their finished chunks in ``<out>/<name>/chunks/``: a killed sweep started again
loads them and computes only the rest.
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
from ..argparsing import make_parser, path_arg
from ..atomic import atomic_write_text
from .config import ConfigError, build_config, config_dir, load_toml

__all__ = ["STUDIES", "ALIASES", "main", "run_args", "add_arguments", "run_study", "resolve", "effective_config",
           "StudyOutcome", "dump_toml"]

#: name -> module (NAME, TITLE, FIGURES, check(cfg), run(ctx) -> summary)
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
    name: str
    out_dir: Path
    summary: dict[str, Any]
    stats: list[Any]
    messages: list[str]


def run_study(name: str, *, quick: bool = False, out: str | os.PathLike[str] = "results", workers: int | None = None,
              scheduler: str | None = None, sets: Sequence[str] = (), config_file: str | os.PathLike[str] | None = None,
              fmu: str | os.PathLike[str] | None = None, max_chunks: int | None = None,
              progress: bool = True) -> StudyOutcome:
    """Run one study (Python API of ``dryfriction study``). Raises ConfigError before any work if
    an argument or config value is invalid, SweepInterrupted if ``max_chunks`` stopped a sweep."""
    from ..sweep.engine import EngineOptions
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
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ConfigError(f"cannot create the output folder {out_dir}: {e.strerror}") from None
    if not os.access(out_dir, os.W_OK):
        raise ConfigError(f"the output folder {out_dir} is not writable")

    opts = EngineOptions(fmu=fmu_path, workers=n_workers, scheduler=scheduler, progress=progress,
                         max_chunks=max_chunks)
    ctx = StudyContext(name=key, cfg=cfg, quick=quick, out_dir=out_dir, engine_options=opts)
    atomic_write_text(out_dir / "config.toml", dump_toml(cfg, header=f"effective configuration of study {key}"
                                                          + (" (--quick)" if quick else "")))
    try:
        summary = STUDIES[key].run(ctx)
    finally:
        stats = list(ctx._engine.stats) if ctx._engine is not None else []
        ctx.close()
    record = {"study": key, "quick": quick, "summary": summary,
              "sweeps": [s.__dict__ for s in stats]}
    atomic_write_text(out_dir / "summary.json", json.dumps(record, indent=2, default=float) + "\n")
    return StudyOutcome(key, out_dir, summary, stats, ctx.messages)


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
    (:func:`dryfriction.console.guarded`), as from ``dryfriction study``."""
    from ..console import guarded

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
    from ..console import PREFIX, interrupt_note, interrupted
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
        fmu = getattr(args, "fmu", None)
        interrupt_note("finished chunks are kept, run again to resume")
        for n in names:
            print(f"== study {n}: {STUDIES[n].TITLE}", flush=True)
            run_study(n, quick=args.quick, out=args.out, workers=args.workers, scheduler=args.scheduler,
                      sets=args.sets, config_file=args.config, fmu=fmu, max_chunks=args.max_chunks,
                      progress=not args.no_progress)
        return EXIT_OK
    except SweepInterrupted as e:
        print(f"{PREFIX}: {e}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except RuntimeError as e:
        if interrupted() or isinstance(e, FMUError):  # said by the caller: the interrupt, exit 2
            raise
        print(f"{PREFIX}: error: {e}", file=sys.stderr)
        return EXIT_FAILED
