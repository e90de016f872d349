"""Work and memory bounded before a computation starts.

Every command (its ``work(args)``, :func:`dryfriction.cli.command_work`) and
:func:`dryfriction.analysis.response.frequency_response` estimate, from their arguments alone, the
work they are about to do and the memory they will hold, and refuse with one line naming the
option and the limit what would exceed the bound, unless the user raises it (``--max-work`` on the
command line, ``max_work=`` in the API).

**The unit of work is one internal step of a Bossak scheme** (one time step of the FMU: about 16
ns of one core, measured on the 2-core development machine). An excitation period of the exact
scheme (closed form from event to event, about 0.7 microseconds) counts as
:data:`EXACT_PERIOD_STEPS` steps, a frequency of the orbit method as its measured cost
(:data:`dryfriction.analysis.response.ORBIT_FREQUENCY_STEPS`), a sampled point of a trajectory as
:data:`SAMPLE_STEPS`, and a step of the chain once per block. The estimate is an upper bound
where the computation has one (the transient method's period limit, a sweep's stop times), else
the typical count (the orbit method's Newton iterations).

**The default bound is** :data:`DEFAULT_MAX_WORK` = 1e10 steps, a few minutes of one core: every
command of docs/cli.md and every study's default configuration is within it (the largest study,
fig10_11_orbits, is 8.0e9 in all: a study's :class:`Estimate` sums every part it runs);
``dryfriction response ... --num 100000000`` (1.2e12) and 10^6 frequencies through the API
(1.2e10) are not.

Memory: the estimate of what the command holds at once (results in this process, a task's
arguments) is compared with half of this machine's memory (:func:`memory_limit`); more is refused
whatever ``--max-work`` says, with the option that makes it large named.
"""

from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from .errors import UsageError

__all__ = ["WorkBoundError", "DEFAULT_MAX_WORK", "EXACT_PERIOD_STEPS", "BOSSAK_PERIOD_STEPS", "SAMPLE_STEPS",
           "check_work", "check_memory", "memory_limit", "max_work_value", "check_writable", "fmt", "Estimate",
           "period_steps", "continuation_work"]

#: the default bound of a command's work, in steps (module doc)
DEFAULT_MAX_WORK = 1e10
#: steps one excitation period of the exact scheme counts as (a few stick/slip events, each a closed
#: form with its root finding: measured 0.7 microseconds, about 45 Bossak steps)
EXACT_PERIOD_STEPS = 50.0
#: steps one sampled communication point of a trajectory counts (a doStep call and its outputs read
#: back through Python: measured about 5 microseconds)
SAMPLE_STEPS = 300.0
#: steps per period of a Bossak scheme whose step is derived (h = 0: the step rule's typical count)
BOSSAK_PERIOD_STEPS = 1000.0


class WorkBoundError(UsageError):
    """A computation refused before it starts: its estimated work or memory exceeds the bound
    (one line naming the option and the limit; exit status 2 on the command line)."""


def fmt(x: float) -> str:
    """A count for a message: 3 significant digits, plain below 10^6."""
    return f"{x:,.0f}" if x < 1e6 else f"{x:.3g}"


def max_work_value(max_work: float | None) -> float:
    """The bound in force: ``max_work`` (checked: a number > 0) or :data:`DEFAULT_MAX_WORK`."""
    if max_work is None:
        return DEFAULT_MAX_WORK
    if isinstance(max_work, bool) or not isinstance(max_work, (int, float)) or not max_work > 0:
        raise WorkBoundError(f"max_work must be a number > 0 (steps), not {max_work!r}")
    return float(max_work)


def check_work(work: float, what: str, max_work: float | None = None, option: str = "--max-work") -> float:
    """Refuse (:class:`WorkBoundError`) when ``work`` (steps) exceeds the bound; ``what`` says what
    the work is made of (``"41 frequencies x 16,384 periods x 20 steps"``). Returns ``work``."""
    bound = max_work_value(max_work)
    if not math.isfinite(work) or work > bound:
        raise WorkBoundError(
            f"about {fmt(work)} steps of work ({what}) exceed the bound {option} {fmt(bound)} (steps); "
            f"ask for less or raise {option}")
    return work


def period_steps(scheme: object, steps_per_period: float) -> float:
    """Steps one excitation period counts: :data:`EXACT_PERIOD_STEPS` for the exact scheme, else
    ``steps_per_period`` (h = T / steps_per_period)."""
    return EXACT_PERIOD_STEPS if str(scheme).lower() in ("exact", "4") else float(steps_per_period)


def continuation_work(max_points: int, max_branches: int, period: int = 1) -> tuple[float, str]:
    """A continuation's work (exact scheme): every point of every branch, about 10 periods of
    Newton's corrector each."""
    pts = int(max_points) * int(max_branches)
    periods = pts * 10 * int(period)
    return periods * EXACT_PERIOD_STEPS, (f"{fmt(pts)} points x about {10 * int(period)} periods x "
                                          f"{EXACT_PERIOD_STEPS:g} steps")


@dataclass
class Estimate:
    """What a computation (a study) will do, from its configuration alone: its work in steps, part
    by part (a sweep, a batch, a trajectory), and the bytes it will write (results and chunks)."""

    #: (what, steps) of every part, in the order they run
    parts: list[tuple[str, float]] = field(default_factory=list)
    #: bytes of the results and chunk files written
    out_bytes: float = 0.0
    #: bytes held in memory at once, at most (the largest part's tables and results)
    memory: float = 0.0

    def add(self, what: str, steps: float, nbytes: float = 0.0, memory: float | None = None) -> "Estimate":
        """Count a part of ``steps`` steps writing ``nbytes`` bytes and holding ``memory`` bytes
        (default: twice ``nbytes``, its results and their dataset); returns self."""
        self.parts.append((what, float(steps)))
        self.out_bytes += float(nbytes)
        self.memory = max(self.memory, 2.0 * float(nbytes) if memory is None else float(memory))
        return self

    def runs(self, what: str, runs: float, periods: float, steps_per_period: float, nbytes: float = 0.0,
             memory: float | None = None) -> "Estimate":
        """Count ``runs`` runs of ``periods`` periods at ``steps_per_period`` steps each."""
        return self.add(f"{what}: {fmt(runs)} runs x {fmt(periods)} periods x {fmt(steps_per_period)} steps",
                        runs * periods * steps_per_period, nbytes, memory)

    @property
    def total(self) -> float:
        """All parts' steps."""
        return float(sum(s for _, s in self.parts))

    def describe(self, limit: int = 3) -> str:
        """The largest parts (at most ``limit``; those of no work, the figures, left out) for a
        message, with how many more there are."""
        big = sorted((p for p in self.parts if p[1] > 0), key=lambda p: -p[1])
        text = "; ".join(w for w, _ in big[:limit])
        return text + (f"; and {len(big) - limit} smaller parts" if len(big) > limit else "")

    def check(self, name: str, max_work: float | None = None, option: str = "--set") -> float:
        """Refuse (:class:`WorkBoundError`) when the total exceeds the bound (``--max-work``), or
        the memory half this machine's (``option`` makes it large). Returns the total."""
        check_work(self.total, f"{name}: {self.describe()}", max_work)
        check_memory(self.memory, f"{name}: {self.describe(1)}", option)
        return self.total


def memory_limit() -> float:
    """Half of this machine's physical memory, bytes (4 GB where it cannot be read)."""
    try:
        return 0.5 * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 4e9


def check_memory(nbytes: float, what: str, option: str) -> float:
    """Refuse when the estimated memory ``nbytes`` exceeds :func:`memory_limit`; ``option`` is the
    one that makes it large."""
    limit = memory_limit()
    if nbytes > limit:
        raise WorkBoundError(f"about {nbytes / 1e9:.3g} GB of memory ({what}) exceed half this machine's memory "
                             f"({limit / 1e9:.3g} GB); ask for less ({option})")
    return nbytes


def check_writable(folder: str | os.PathLike[str], nbytes: float = 0.0, what: str = "",
                   option: str = "--out") -> Path:
    """Before the work: ``folder`` can take a result set (:func:`dryfriction.atomic.check_output_folder`:
    a probe created and removed where the set will be staged; nothing is left behind, no folder
    created), and its file system has room for ``nbytes`` (with a margin); a :class:`UsageError`
    naming ``option``, the folder and the cause otherwise."""
    from .atomic import check_output_folder, nearest_existing

    d = check_output_folder(folder, option)
    if nbytes > 0:
        free = shutil.disk_usage(nearest_existing(d)).free
        if free < 1.2 * nbytes + 1e6:
            raise UsageError(f"the output folder {d} has {free / 1e6:.3g} MB free, {what or 'the results'} "
                             f"need about {nbytes / 1e6:.3g} MB")
    return d
