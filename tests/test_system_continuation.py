"""A structure's continuation (dryfriction.analysis.system_continuation: the located map with the FMU's
Jacobian, the project's one continuation engine) locates the bifurcations of the oscillator's exact
continuation, within the scheme's error: the one-DOF structure is the oscillator
(``System.from_oscillator``), so its fold in frequency (the four-stop motion of Fig. 11/14) and the
period doubling of the Fig. 8/9 band's asymmetric branch (in mu_k, chi = mu_k / mu_s) must fall
where the exact map puts them (tests/test_continuation.py: lambda 0.1725095929, chi 0.2367840452),
to O(h^2) at h = T/2000 (measured 7.6e-6 and 4.6e-6). The branches stay on their curve (no point
further from the last than a few steps) and the doubled branch is a true 2-period orbit of a
separate FMU's map.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dryfriction import Oscillator, System, continue_orbits, find_orbits
from dryfriction.analysis.system_orbits import system_map
from dryfriction.drivers.system import SystemFMU3

pytestmark = pytest.mark.slow

LAM_FOLD = 0.1725095929       # the exact map's fold (tests/test_continuation.py)
CHI_PD = 0.2367840452         # the exact map's period doubling on the asymmetric branch


def structure(p: Oscillator) -> System:
    return System.from_oscillator(p).replace(h=2 * np.pi / p.omega / 2000)


def test_the_fold_in_frequency_of_the_four_stop_motion() -> None:
    p = Oscillator.from_nondimensional(lam=0.15, mu_s_sigma=0.6, chi=0.7, phi=0.7)
    (o4,) = [o for o in find_orbits(p) if o.events["transitions"] == 8]
    s = structure(p)
    (so,) = [o for o in find_orbits(s, guesses=[[o4.x0, o4.v0]]) if abs(o.amplitude[0] / o4.amplitude - 1) < 1e-3]
    w0 = p.w0
    c = continue_orbits(s, "omega", p.omega, 0.2 * w0, ds=0.2, orbit=so, max_points=30)
    (f,) = [b for b in c.bifurcations if b.type == "fold"]
    assert f.note == "" and abs(f.multipliers[0] - 1.0) <= 1e-6
    assert abs(f.param / w0 - LAM_FOLD) < 2e-5, f.param / w0
    lam = c.dataset.param.values / w0
    i = int(np.argmax(lam))
    assert lam.max() <= f.param / w0 + 1e-12 and bool(c.dataset.stable[0]) and not bool(c.dataset.stable[i + 1])
    # on its curve: from the start up to the fold and back, each step short
    assert lam.min() >= 0.15 - 1e-12 and np.all(np.abs(np.diff(lam)) < 0.02)


def asymmetric_branch(chi_stop: float) -> tuple[Oscillator, System, object]:
    """The Fig. 8/9 band's asymmetric branch of the one-DOF structure continued in mu_k from chi = 0.5
    (its start the structure's orbit next to the exact map's stable one of positive offset) to chi_stop."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.5)
    asym = max((o for o in find_orbits(p) if o.stable), key=lambda o: o.offset)
    s = structure(p)
    (so,) = [o for o in find_orbits(s, guesses=[[asym.x0, asym.v0]]) if abs(o.offset[0] / asym.offset - 1) < 1e-3]
    return p, s, continue_orbits(s, "mu_k", p.mu_k, chi_stop * p.mu_s, orbit=so, ds=0.02, max_points=60)


def test_the_period_doubling_of_the_asymmetric_branch() -> None:
    p, s, c = asymmetric_branch(0.22)
    (pd,) = [b for b in c.bifurcations if b.type == "period_doubling"]
    assert abs(pd.multipliers[0] + 1.0) <= 1e-6 and pd.period == 1
    assert abs(pd.param / p.mu_s - CHI_PD) < 2e-5, pd.param / p.mu_s
    (child,) = pd.children
    d = c.dataset.where(c.dataset.branch == child, drop=True)
    assert np.all(d.period.values == 2) and bool(d.converged.all())
    # a true 2-period orbit: two periods of a separate map run return to it, one does not
    k = int(np.argmin(d.param.values))
    sk = s.replace(contacts=[dataclasses.replace(s.contacts[0], mu_k=float(d.param[k]))])
    z = np.array([float(d.x0[k, 0]), float(d.v0[k, 0])])
    scale = float(d.amplitude_m[k, 0])
    assert np.abs(system_map(sk, z, period=2)[0] - z).max() / scale <= 1e-6
    assert np.abs(system_map(sk, z, period=1)[0] - z).max() / scale > 1e-2


CHI_GRAZING = 0.5346710662    # the exact map's grazing on the asymmetric branch (tests/test_continuation.py)


def test_the_grazing_where_a_reversal_turns_into_a_stop() -> None:
    """Up the asymmetric branch from chi = 0.5 the direct reversal of the cycle (3 mode changes)
    turns into a stop, a short stick and a breakaway (4) where the exact map puts it; the arclength
    corrector does not converge across that corner, and the walk crosses it at fixed parameters
    and goes on. The FMU's counts on either side (transitions, per contact) from separate solves."""
    p, _, c = asymmetric_branch(0.545)
    (g,) = [b for b in c.bifurcations if b.type == "grazing"]
    assert abs(g.param / p.mu_s - CHI_GRAZING) < 2e-5, g.param / p.mu_s
    assert g.events == ((((3, True, True),), True), (((4, True, True),), True))
    chi = c.dataset.param.values / p.mu_s
    tr = c.dataset.transitions.values
    assert chi.max() >= 0.545 - 1e-9 and bool(c.dataset.converged.all())
    assert np.all(tr[chi < g.param / p.mu_s - 1e-9] == 3) and np.all(tr[chi > g.param / p.mu_s + 1e-6] == 4)
    for d, count in ((-1e-4, 3), (1e-4, 4)):
        q = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=CHI_GRAZING + d)
        qa = max((o for o in find_orbits(q) if o.stable), key=lambda o: o.offset)
        with SystemFMU3(structure(q)) as fmu:
            fmu.start(0.0, x0=[qa.x0], v0=[qa.v0], t_obs_start=0.0, t_obs_stop=q.period)
            fmu.do_step(q.period)
            assert fmu.transitions().tolist() == [count]


CHI_SB = 0.5539500960          # the exact map's symmetry breaking of the Fig. 8/9 band's symmetric branch


def test_the_symmetry_breaking_and_its_mirror_branches() -> None:
    """Down the band's symmetric branch from chi = 0.8 (continued on the half-period map H =
    -P^{1/2}), H's multiplier passes -1 where the exact map puts the symmetry breaking; the two mirror
    branches off it are followed (each other's mirror image: offsets of opposite sign) through the
    grazing where a reversal turns into a stop. Independent: orbits found on either side, one
    symmetric stable orbit above, a stable mirror pair below."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.8)
    s = structure(p)
    c = continue_orbits(s, "mu_k", p.mu_k, 0.5 * p.mu_s, ds=0.02, max_points=80)
    (sb,) = [b for b in c.bifurcations if b.type == "symmetry_breaking"]
    assert abs(sb.param / p.mu_s - CHI_SB) < 2e-5, sb.param / p.mu_s
    assert c.branches[0].kind == "symmetric" and abs(sb.half_multipliers[np.argmin(np.abs(sb.half_multipliers + 1))] + 1) <= 1e-6
    a, b = (c.dataset.where(c.dataset.branch == i, drop=True) for i in sb.children)
    assert bool(a.converged.all()) and bool(b.converged.all())
    end_a, end_b = float(a.offset_m[-1, 0]), float(b.offset_m[-1, 0])
    assert float(a.param[-1]) == float(b.param[-1]) == pytest.approx(0.5 * p.mu_s)
    assert end_a == pytest.approx(-end_b, rel=1e-6) and abs(end_a) > 1e-3
    g = [x for x in c.bifurcations if x.type == "grazing"]
    assert len(g) == 2 and {x.branch for x in g} == set(sb.children)
    assert all(abs(x.param / p.mu_s - 0.5346710662) < 2e-5 for x in g)
    for d, count in ((2e-3, 1), (-2e-3, 2)):
        chi = sb.param / p.mu_s + d
        q = System.from_oscillator(Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=chi)).replace(h=s.h)
        near = [br.isel(point=int(np.argmin(np.abs(br.param.values / p.mu_s - chi))))
                for br in (a, b, c.dataset.where(c.dataset.branch == 0, drop=True))]
        found = [o for o in find_orbits(q, guesses=[[float(x.x0[0]), float(x.v0[0])] for x in near]) if o.stable]
        offsets = sorted({round(float(o.offset[0]), 6) for o in found})
        assert len(offsets) == count, offsets
