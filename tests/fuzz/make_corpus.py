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
      "alpha": 12, "scheme": 15, "frictionUpdates": 16, "observe": 17, "fastPaths": 18, "F_ext": 19, "N_ext": 20,
      "v_belt": 38}


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
    # the exact scheme on a moving belt, the belt changed at communication points (a stuck block slides)
    "exact_belt": seti("scheme", 4) + setup(0.0) + setr("v_belt", 0.3) + bytes([ENTER, EXIT]) + step(3000) * 3
    + setr("v_belt", -0.2) + step(2000) * 2 + setr("v_belt", 0.0) + step(3000) + bytes([GETR, OUTS])
    + bytes([GETS, 0, SER, 0, DESER, 0, 1, SETS, 1]) + setr("F_ext", 0.5) + step(500),
    "late_start": setup(1e6) + bytes([ENTER, EXIT]) + step(100) * 3,
    "logging": bytes([LOG, 0, LOG, 0b10000111, LOG, 1, INST, 1, 1]) + setup(0.0) + bytes([ENTER, EXIT])
    + step(1000) + bytes([STATUS, 2, OUTS]),
}

# fuzz_chain3.c (u8 % 22): the chain's FMI 3.0 sessions, written to tests/fuzz/corpus_chain3/
C_INST, C_FREE, C_CFG, C_SETN, C_EXITCFG, C_ENTER, C_EXIT = 0, 1, 2, 3, 5, 6, 7
C_ARR, C_SCAL, C_GET, C_STEP, C_EVENT, C_TERM, C_GETS, C_SETS, C_SER, C_DESER = 8, 10, 11, 12, 15, 16, 17, 18, 19, 20
N_INDEX = {1: 0, 2: 1, 3: 2, 5: 3, 8: 4, 13: 5, 0: 8, 4097: 9, 64: 10, 4096: 11}  # any_n's table


def c_config(n: int) -> bytes:  # configuration mode, n, leave
    return bytes([C_CFG, C_SETN, 0, N_INDEX[n], 255, C_EXITCFG])


def c_start(flags: int, n: int) -> bytes:
    return bytes([C_INST, flags]) + c_config(n) + bytes([C_ENTER, 0, 0, 0, C_EXIT])


def c_step(fine: bool = False) -> bytes:  # dt 0.1 (0.01), at the FMU's time
    return bytes([C_STEP, 24 if fine else 23, 0])


def c_array(slot: int, n: int, code: int = 100, wrong: bool = False) -> bytes:
    """Array slot 1..12 (m ... N_ext): n values (wrong: 4) of one value, real()'s selector code
    (< 52: a special value; 52 ... 235: from the next two bytes)."""
    count = bytes([3, 4]) if wrong else bytes([255])
    value = bytes([code]) + (bytes([0x40, 0x80]) if 52 <= code < 236 else b"")
    return bytes([C_ARR, 0, slot - 1]) + count + value + bytes(4 if wrong else n)


CHAIN3_SEEDS = {
    "plain": c_start(0, 3) + c_step() * 20 + bytes([C_GET, 0, 0, 0]),
    "early_event": c_start(0b011, 5) + bytes([C_EVENT, 2]) + (c_step() + bytes([C_EVENT, 0, C_EVENT, 1, C_EVENT, 2])) * 15,
    "update": c_start(0b01110, 2) + c_step() * 30,
    "states": c_start(0, 8) + c_step() * 5 + bytes([C_GETS, 0, C_SER, 0, C_DESER, 0, 1, C_SETS, 1]) + c_step() * 5
    + bytes([C_DESER, 2, 10, 0, 7, 0, C_DESER, 1, 4, 0, 0, C_SETS, 0]),
    "arrays": bytes([C_INST, 0]) + c_config(13) + c_array(1, 13) + c_array(6, 13, wrong=True) + c_array(1, 13, code=2)
    + bytes([C_ENTER, 0, 0, 0, C_EXIT]) + c_array(11, 13) + c_step(True) * 10,
    "sizes": bytes([C_INST, 0]) + c_config(0) + c_config(4097) + c_config(1) + bytes([C_ENTER, 0, 0, 0, C_EXIT])
    + c_step() * 3 + bytes([C_GETS, 0, C_TERM, 0, C_CFG]) + c_config(2) + bytes([C_SETS, 0]) + c_step(),
}


def main() -> None:
    here = Path(__file__).resolve().parent
    for folder, seeds in (("corpus", SEEDS), ("corpus_chain3", CHAIN3_SEEDS)):
        out = here / folder
        out.mkdir(exist_ok=True)
        for name, data in seeds.items():
            tmp = out / f".{name}.tmp"
            tmp.write_bytes(data)
            tmp.replace(out / f"seed_{name}")
        print(f"wrote {len(seeds)} seeds to {out}")


if __name__ == "__main__":
    main()
