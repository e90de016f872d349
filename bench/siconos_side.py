"""Getting Siconos and talking to it, from the project's .venv.

Siconos is Debian's ``python3-siconos``, built for the system Python (``/usr/bin/python3``), not
for the .venv: :func:`ensure_siconos` installs it with apt-get when it is missing (as root, else
through ``sudo -n``; waiting up to 10 minutes for the dpkg lock), :func:`compile_plugin` builds the
C plugin that computes the harmonic force b(t) (so no Python runs per Siconos step), and
:class:`SiconosWorker` runs ``bench/siconos_run.py`` under the system Python as one long-lived
subprocess, one JSON line per job each way.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
RUNNER = HERE / "siconos_run.py"
SYSTEM_PYTHON = os.environ.get("DFO_SICONOS_PYTHON", "/usr/bin/python3")
PACKAGE = "python3-siconos"

# b(t) of x' = A x + b(t) + B lambda for x = (X, V) of n blocks: z = (omega, P0_i/m_i, phi_i)
PLUGIN_C = r"""
#include <math.h>

void dfo_harmonic_b(double t, unsigned int size, double *b, unsigned int zsize, double *z);

void dfo_harmonic_b(double t, unsigned int size, double *b, unsigned int zsize, double *z)
{
    unsigned int n = size / 2u, i;
    (void)zsize;
    for (i = 0; i < n; i++) {
        b[i] = 0.0;
        b[n + i] = z[1u + i] * cos(z[0] * t + z[1u + n + i]);
    }
}
"""


class SiconosUnavailable(RuntimeError):
    """Siconos could not be imported nor installed: the message says why."""


def _importable() -> tuple[bool, str]:
    if not Path(SYSTEM_PYTHON).is_file():
        return False, f"{SYSTEM_PYTHON} does not exist"
    r = subprocess.run([SYSTEM_PYTHON, "-c", "import siconos.kernel, siconos.numerics"],
                       capture_output=True, text=True, timeout=120)
    return r.returncode == 0, (r.stderr.strip().splitlines() or [""])[-1]


def ensure_siconos(log=sys.stderr) -> str:
    """Make ``import siconos.kernel`` work under the system Python, installing python3-siconos
    with apt-get when needed. Returns the Debian package version; raises SiconosUnavailable."""
    ok, why = _importable()
    if not ok:
        if shutil.which("apt-get") is None:
            raise SiconosUnavailable(f"siconos is not importable by {SYSTEM_PYTHON} ({why}) and there is no apt-get")
        sudo: list[str] = [] if os.geteuid() == 0 else ["sudo", "-n"]
        apt = ["env", "DEBIAN_FRONTEND=noninteractive", *sudo, "apt-get", "-o", "DPkg::Lock::Timeout=600"]
        log.write(f"siconos: not importable ({why}); installing {PACKAGE} with apt-get ...\n")
        r = subprocess.run([*apt, "install", "-y", "-q", "--no-install-recommends", PACKAGE],
                           capture_output=True, text=True)
        if r.returncode != 0:
            subprocess.run([*apt, "update", "-q"], capture_output=True, text=True)
            r = subprocess.run([*apt, "install", "-y", "-q", "--no-install-recommends", PACKAGE],
                               capture_output=True, text=True)
        if r.returncode != 0:
            last = (r.stderr.strip().splitlines() or r.stdout.strip().splitlines() or ["?"])[-1]
            raise SiconosUnavailable(f"apt-get install {PACKAGE} failed: {last}")
        ok, why = _importable()
        if not ok:
            raise SiconosUnavailable(f"{PACKAGE} installed but {SYSTEM_PYTHON} cannot import siconos: {why}")
    r = subprocess.run(["dpkg-query", "-W", "-f", "${Version}", PACKAGE], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else "unknown"


def compile_plugin(folder: Path) -> Path:
    """The b(t) plugin as a shared library in folder (cc, -Wall -Wextra -Werror)."""
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        raise SiconosUnavailable("no C compiler (cc) to build the Siconos b(t) plugin")
    src = folder / "dfo_siconos_b.c"
    lib = folder / "dfo_siconos_b.so"
    src.write_text(PLUGIN_C)
    r = subprocess.run([cc, "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC",
                        "-o", str(lib), str(src), "-lm"], capture_output=True, text=True)
    if r.returncode != 0:
        raise SiconosUnavailable(f"compiling the b(t) plugin failed: {r.stderr.strip()}")
    return lib


class SiconosWorker:
    """bench/siconos_run.py under the system Python; :meth:`run` sends one job and waits for its
    answer. Use as a context manager."""

    def __init__(self) -> None:
        self._dir = Path(tempfile.mkdtemp(prefix="dfo_siconos_"))
        plugin = compile_plugin(self._dir)
        self._err = open(self._dir / "stderr.txt", "w+")
        self.proc = subprocess.Popen([SYSTEM_PYTHON, str(RUNNER), str(plugin)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=self._err, text=True, bufsize=1)
        hello = self._read()
        self.module_version = str(hello.get("siconos", "?"))
        self.python = str(hello.get("python", "?"))

    def _read(self) -> dict[str, Any]:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            self._err.seek(0)
            tail = self._err.read().strip().splitlines()[-5:]
            raise RuntimeError("the Siconos worker stopped: " + " | ".join(tail))
        return json.loads(line)

    def run(self, job: dict[str, Any]) -> dict[str, Any]:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(job) + "\n")
        self.proc.stdin.flush()
        res = self._read()
        if "error" in res:
            raise RuntimeError(f"Siconos job {job.get('id')} failed: {res['error']}")
        return res

    def close(self) -> None:
        if self.proc.poll() is None:
            assert self.proc.stdin is not None
            self.proc.stdin.close()
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._err.close()
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> "SiconosWorker":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
