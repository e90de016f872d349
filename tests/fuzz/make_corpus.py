"""Write the seed inputs of tests/fuzz/corpus/ (byte programs for fuzz_fmi.c's decoder).

Each seed is a plausible FMI session; libFuzzer mutates from there. Run from anywhere:
    python tests/fuzz/make_corpus.py
"""

from __future__ import annotations

import struct
from pathlib import Path

# op codes of fuzz_fmi.c (u8 % 20)
INST, SETUP, ENTER, EXIT, SETR, SETI, SETB, STEP, GETR, GETIB, TERM, RESET = range(12)
GETS, SETS, FREES, SER, DESER, LOG, STATUS, OUTS = range(12, 20)
VR = {"m": 0, "k": 1, "c": 2, "P0": 3, "omega": 4, "N": 6, "mu_s": 7, "chi": 8, "x0": 9, "v0": 10, "h": 11,
      "alpha": 12, "scheme": 15, "frictionUpdates": 16, "observe": 17, "fastPaths": 18, "F_ext": 19, "N_ext": 20}


def raw(x: float) -> bytes:
    """real(): selector >= 224 then 8 raw bytes (two little-endian u32)."""
    return bytes([255]) + struct.pack("<d", x)


def setr(name: str, x: float) -> bytes:
    return bytes([SETR, 0, VR[name]]) + raw(x)


def step(n: int) -> bytes:  # doStep at the host time, dt = (1 + n) 1e-4
    return bytes([STEP, 0]) + struct.pack("<H", n)


def seti(name: str, v: int) -> bytes:  # integer(): selector 200+ then raw u32
    return bytes([SETI, VR[name], 255]) + struct.pack("<i", v)


def setup(start: float) -> bytes:
    return bytes([SETUP, 4]) + raw(start)


SEEDS = {
    "basic": setup(0.0) + setr("h", 1e-3) + bytes([ENTER, EXIT]) + step(99) * 5 + bytes([GETR, OUTS, TERM]),
    "observe": setup(0.0) + bytes([SETB, VR["observe"], 1]) + setr("chi", 0.3) + bytes([ENTER, EXIT])
    + step(500) * 4 + bytes([GETR]),
    "states": setup(0.0) + bytes([ENTER, EXIT]) + step(50) + bytes([GETS, 0, SER, 0, DESER, 0, 1, SETS, 1])
    + step(50) + bytes([DESER, 2, 10, 0, 7, 0, DESER, 3, 4, 0, 255]) + struct.pack("<d", 0.0)
    + bytes([0, SETS, 0, FREES, 0, FREES, 1]),
    "schemes": b"".join(seti("scheme", s) + setup(0.0) + bytes([ENTER, EXIT]) + step(300) * 3 + bytes([RESET])
                        for s in (1, 2, 3)),
    "inputs": setup(0.0) + bytes([ENTER, EXIT]) + step(10) + setr("F_ext", 0.8) + step(10) + setr("N_ext", -0.5)
    + step(200) + bytes([GETR]),
    "misuse": bytes([STEP, 0, 1, 0, EXIT, GETR, ENTER, ENTER, SETUP, 0]) + setr("m", -1.0)
    + bytes([EXIT]) + step(3) + bytes([STEP, 3, 0, 255]) + struct.pack("<d", -1.0) + bytes([TERM, STEP, 0, 1, 0]),
    "late_start": setup(1e6) + bytes([ENTER, EXIT]) + step(100) * 3,
    "logging": bytes([LOG, 0, LOG, 0b10000111, LOG, 1, INST, 1, 1]) + setup(0.0) + bytes([ENTER, EXIT])
    + step(1000) + bytes([STATUS, 2, OUTS]),
}


def main() -> None:
    out = Path(__file__).resolve().parent / "corpus"
    out.mkdir(exist_ok=True)
    for name, data in SEEDS.items():
        tmp = out / f".{name}.tmp"
        tmp.write_bytes(data)
        tmp.replace(out / f"seed_{name}")
    print(f"wrote {len(SEEDS)} seeds to {out}")


if __name__ == "__main__":
    main()
