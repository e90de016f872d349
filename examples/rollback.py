"""A rollback with FMU states: save the state, try a step, go back, try another input; and the
same through serialised bytes (as a master that checkpoints to disk would).

Uses the public OscillatorFMU2.get_state / set_state / serialize_state / restore; no fmpy objects.

    python examples/rollback.py
"""

from __future__ import annotations

from dryfriction import Oscillator
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings


def main() -> None:
    block = Oscillator.physical(m=0.5, k=2000.0, P0=10.0, f=10.0, N=20.0, mu_s=0.3, mu_k=0.2)
    dt = block.period / 50
    with OscillatorFMU2() as fmu:
        fmu.start(block, Settings(h=0.0))
        fmu.step_to(10 * dt)
        saved = fmu.get_state()                       # an FMU state (inputs included)
        data = fmu.serialize_state(saved)             # the same as bytes
        t_saved = fmu.time

        fmu.set({"F_ext": 50.0})                      # try a large push ...
        fmu.step_to(t_saved + dt)
        pushed = fmu.get(("x",))["x"]

        fmu.set_state(saved)                          # ... roll back (time and input follow the state)
        assert fmu.time == t_saved
        fmu.step_to(t_saved + dt)
        plain = fmu.get(("x",))["x"]

        fmu.restore(data)                             # from the serialised bytes
        fmu.step_to(t_saved + dt)
        again = fmu.get(("x",))["x"]
        saved.free()
    print(f"t = {t_saved + dt:.5f} s: x with the push {1000 * pushed:.4f} mm, after the rollback {1000 * plain:.4f} mm")
    print(f"after restoring the serialised state: {1000 * again:.4f} mm (bit-identical: {again == plain})")
    if again != plain or pushed == plain:
        raise SystemExit("rollback did not reproduce the run")


if __name__ == "__main__":
    main()
