"""The chain driver's own logic, without an FMU: array parameters (a scalar for every block, n
values, one sentence otherwise), the command's argument parsing, the trajectory's derived numbers
and the wave study's front measures. (The command's one-line errors: test_cli_errors.py.)"""

from __future__ import annotations

import numpy as np
import pytest

from dryfriction.errors import UsageError
from dryfriction.drivers.chain import ChainRun, expand
from dryfriction.cli.chain import parse_sets
from dryfriction.studies.chain_waves import first_slip, front_speed


def test_expand_scalar_list_and_errors() -> None:
    assert np.array_equal(expand("mu_s", 0.3, 4), [0.3] * 4)
    assert np.array_equal(expand("P0", [1, 0, 0], 3), [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"^m needs 8 values \(one per block, n = 8\) or one value for every "
                                         r"block, not 3$"):
        expand("m", [1.0, 2.0, 3.0], 8)
    with pytest.raises(ValueError, match=r"invalid value inf for N\[2\]; valid range: finite"):
        expand("N", [1.0, np.inf], 2)
    with pytest.raises(ValueError, match="must be a number or a list of 2 numbers"):
        expand("k", "stiff", 2)
    with pytest.raises(ValueError, match="not an array of shape"):
        expand("k", [[1.0, 2.0]], 2)


def test_parse_sets() -> None:
    assert parse_sets(["mu_s=0.3", "P0=1,0,0", "scheme=consistent", "scheme=2"]) == {
        "mu_s": 0.3, "P0": [1.0, 0.0, 0.0], "scheme": 2}
    with pytest.raises(UsageError, match="--set needs NAME=VALUE"):
        parse_sets(["mu_s"])
    with pytest.raises(UsageError, match="--set N: 'heavy' is not a number"):
        parse_sets(["N=heavy"])


def test_chain_run_derived_numbers() -> None:
    t = np.linspace(0.0, 4.0, 5)
    x = np.array([[0.0, 1.0], [1.0, 1.0], [-1.0, 1.0], [3.0, 1.0], [2.0, 1.0]])
    mode = np.array([[0, 0], [1, 0], [-1, 0], [1, 0], [0, 0]], dtype=np.int8)
    z = np.zeros_like(x)
    r = ChainRun(t, x, z, z, z, mode, {"n": 2})
    assert np.array_equal(r.amplitude(), [2.0, 0.0])
    assert np.array_equal(r.amplitude(t_from=2.0), [2.0, 0.0])
    assert np.array_equal(r.stick_share(), [0.4, 1.0])
    assert np.array_equal(r.stick_share(t_from=3.0), [0.5, 1.0])
    ds = r.to_dataset()
    assert ds.x.dims == ("time", "block") and list(ds.block.values) == [1, 2]
    assert ds.attrs["param_n"] == 2 and ds.x.attrs["units"] == "m"


def test_front_measures() -> None:
    """A front that reaches block j at t = 2 j (0.5 blocks/s) and stops after block 5."""
    t = np.arange(0.0, 20.0, 0.5)
    mode = np.zeros((t.size, 8), dtype=np.int8)
    for j in range(5):
        mode[t >= 2.0 * j + 1.0, j] = 1 if j % 2 == 0 else -1
    first = first_slip(t, mode)
    assert np.array_equal(first[:5], [1.0, 3.0, 5.0, 7.0, 9.0]) and np.all(np.isnan(first[5:]))
    assert front_speed(first) == pytest.approx(0.5, rel=1e-12)
    assert np.isnan(front_speed(np.array([1.0, np.nan, np.nan])))
