"""The one exception hierarchy (dryfriction.errors): every driver raises an FMUCallError with the
FMU's own sentence for a bad value (the variable named) or a failed step, FMUFileError (an
FMUError and a UsageError) for an unusable file, fmpy's exceptions translated where fmpy is still
called, an exception of the intermediate-update callback raised again, and the command line's exit
status 2 for an FMU error."""

from __future__ import annotations

from pathlib import Path

import pytest

from dryfriction import paths
from dryfriction.errors import UsageError
from dryfriction.drivers.chain import ChainFMU2, ChainFMU3
from dryfriction.errors import FMUCallError, FMUError, FMUFileError
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.drivers.oscillator3 import OscillatorFMU3
from dryfriction.params import Oscillator


def test_the_hierarchy() -> None:
    assert issubclass(FMUCallError, FMUError) and issubclass(FMUFileError, FMUError)
    assert issubclass(FMUFileError, UsageError) and issubclass(FMUFileError, ValueError)
    assert issubclass(FMUError, RuntimeError)
    e = FMUCallError("invalid value -1 for variable m", "fmi3SetFloat64", 3)
    assert str(e) == "fmi3SetFloat64 returned fmi3Error: invalid value -1 for variable m"
    assert (e.message, e.function, e.status) == ("invalid value -1 for variable m", "fmi3SetFloat64", 3)
    assert str(FMUCallError("x", "fmi2DoStep", 2)) == "fmi2DoStep returned fmi2Discard: x"
    assert str(FMUError("no call")) == "no call"


def test_a_bad_value_is_an_fmu_call_error_naming_the_variable(fmu: OscillatorFMU2, chain_fmu2: Path,
                                                               chain_fmu3: Path) -> None:
    # FMI 2.0 oscillator: the FMU's range check of alpha (a value Settings does not check itself)
    with pytest.raises(FMUCallError) as err:
        fmu.start(Oscillator(), Settings(h=1e-3, extra={"alpha": 0.5}))
    assert (err.value.function, err.value.status) == ("fmi2SetReal", 3)
    assert "invalid value 0.5 for variable alpha" in err.value.message and "valid range" in err.value.message
    # FMI 3.0 oscillator: m in Initialization Mode
    with pytest.raises(FMUCallError) as err:
        OscillatorFMU3({"m": -1.0})
    assert (err.value.function, err.value.status) == ("fmi3SetFloat64", 3)
    assert "m" in err.value.message and "valid range: in [1e-100, 1e+100]" in err.value.message, err.value.message
    # the chains: the element named
    with ChainFMU3(3, fmu_path=chain_fmu3) as f:
        with pytest.raises(FMUCallError, match=r"invalid value -1 for m\[3\]") as err:
            f.run(1.0, 0.1, {"m": [1.0, 1.0, -1.0]})
        assert err.value.function == "fmi3SetFloat64" and str(err.value).startswith("fmi3SetFloat64 returned fmi3Error: ")
        with pytest.raises(FMUCallError, match=r"invalid value 5000 for n") as err:
            f.set_n(5000)
            f.run(1.0, 0.1)
        assert err.value.function == "fmi3SetUInt64"
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        bad = [1.0] * (f2.n - 1) + [-2.0]
        with pytest.raises(FMUCallError, match=rf"invalid value -2 for m\[{f2.n}\]") as err:
            f2.run(1.0, 0.1, {"m": bad})
        assert err.value.function == "fmi2SetReal"


def test_a_failed_step_is_an_fmu_call_error_in_both_versions(fmu: OscillatorFMU2) -> None:
    huge = dict(P0=1e307, N=0.0, omega=0.0, k=1e-100)
    fmu.start(Oscillator(**huge), Settings(h=1e-3))
    with pytest.raises(FMUCallError, match="non-finite") as err:
        fmu.do_step(1e6)
    assert (err.value.function, err.value.status) == ("fmi2DoStep", 3)
    with OscillatorFMU3({**huge, "h": 1e-3}) as f3:
        with pytest.raises(FMUCallError, match="non-finite") as err:
            f3.do_step(1e6)
        assert (err.value.function, err.value.status) == ("fmi3DoStep", 3)


def test_an_unusable_file_is_an_fmu_file_error_for_every_driver(tmp_path: Path) -> None:
    bad = tmp_path / "README.md"
    bad.write_text("not an FMU\n")
    for make in (lambda: OscillatorFMU2(bad), lambda: OscillatorFMU3(fmu_path=bad),
                 lambda: ChainFMU2(fmu_path=bad), lambda: ChainFMU3(2, fmu_path=bad)):
        with pytest.raises(FMUFileError, match="is not an FMU \\(not a zip archive\\)") as err:
            make()
        assert isinstance(err.value, FMUError) and isinstance(err.value, UsageError)


def test_fmpys_unzip_error_is_translated(tmp_path: Path, fmu_path: Path) -> None:
    broken = tmp_path / "broken.fmu"
    data = fmu_path.read_bytes()
    broken.write_bytes(data[: len(data) // 2])  # a truncated archive
    with pytest.raises(FMUFileError, match="broken.fmu") as err:
        paths.extract(broken)
    assert "\n" not in str(err.value)


def test_an_exception_in_the_intermediate_update_is_raised_by_the_step() -> None:
    class Stop(Exception):
        pass

    def callback(t: float, can_return: bool) -> bool:
        raise Stop(f"callback at t = {t}")

    with OscillatorFMU3({"h": 1e-3}, early_return=True, intermediate=callback) as f:
        with pytest.raises(Stop, match="callback at t = "):
            f.do_step(2.0)


def test_the_fmpy_style_surface_raises_both_kinds() -> None:
    from fmpy.fmi1 import FMICallException

    with OscillatorFMU3({}, early_return=True) as f:
        with pytest.raises(FMUCallError) as err:
            f.slave.enterEventMode()  # event mode not used
        assert isinstance(err.value, FMICallException) and err.value.function == "fmi3EnterEventMode"


def test_the_cli_exits_2_on_an_fmu_error(tmp_path: Path, chain_fmu3: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from dryfriction.cli import main

    assert main(["chain", "--n", "3", "--set", "m=1,1,-1", "--fmu", str(chain_fmu3), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "fmi3SetFloat64 returned fmi3Error" in err and "invalid value -1 for m[3]" in err
    assert len(err.strip().splitlines()) == 1
