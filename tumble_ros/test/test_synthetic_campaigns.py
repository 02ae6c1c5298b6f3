"""
The synthetic-campaign generator (synthetic_campaigns.py) proven alone, before it proves the fit.

Each check can fail: the rigid body conserves E and L to 1e-10 over weeks; the requested P_psi
and P_phi are what the integrated motion does (zero crossings of w in body axes; the reference
axis' mean turn about L); L points at the requested pole and the phases are the requested ones;
the surface quadrature meets the sphere's closed forms (Lommel-Seeliger and Lambert) at several
phase angles and the ellipsoid's projected area at zero phase, and converges as the grid is
refined; a principal-axis rotator's lightcurve repeats every half period; the two-body orbits
close after a period; light time is Delta / c; the nights avoid the full moon.
"""
import math

import numpy as np
import pytest

import synthetic_campaigns as sc

SAM = sc.TrueSpin('SAM', 11.0, 47.0, (0.55, 0.83), (123.0, -35.0), (0.7, 2.2), epoch_jd=2459000.5)
LAM = sc.TrueSpin('LAM', 9.0, 20.0, (0.5, 0.8), (30.0, 40.0), (0.4, 2.0), True, 2459000.5)


@pytest.fixture(scope='module', params=[SAM, LAM], ids=['SAM', 'LAM'])
def motion(request):
    """(spin, t [d from the epoch], w, C) over 30 days, every 0.02 d."""
    spin = request.param
    t = np.arange(0.0, 30.0, 0.02)
    w, c = sc.integrate_attitude(spin, spin.epoch_jd + t)
    return spin, t, w, c


def test_energy_and_momentum_conserved(motion):
    spin, _t, w, c = motion
    moments = spin.moments
    energy = 0.5 * np.sum(moments * w * w, axis=1)
    momentum = np.einsum('nij,nj->ni', c, moments * w)          # L in the ecliptic frame
    assert np.max(np.abs(energy / energy[0] - 1.0)) < 1e-10
    assert np.max(np.linalg.norm(momentum - momentum[0], axis=1)) \
        < 1e-10 * np.linalg.norm(momentum[0])
    assert np.max(np.abs(np.einsum('nji,njk->nik', c, c) - np.eye(3))) < 1e-9


def test_pole_and_phases_are_the_requested(motion):
    spin, _t, w, c = motion
    momentum = c[0] @ (spin.moments * w[0])
    direction = momentum / np.linalg.norm(momentum)
    lon, lat = np.radians(spin.pole_deg)
    assert direction == pytest.approx([math.cos(lat) * math.cos(lon),
                                       math.cos(lat) * math.sin(lon), math.sin(lat)], abs=1e-12)
    # the L frame -> (a, b, r) matrix at the epoch, read back as z-x-z Euler angles
    abr = sc._abr_to_body(spin.mode)
    to_abr = abr.T @ c[0].T @ sc.l_frame(spin.pole_deg)
    theta = math.acos(to_abr[2, 2])
    psi = math.atan2(to_abr[0, 2], to_abr[1, 2])
    phi = math.atan2(to_abr[2, 0], -to_abr[2, 1])
    assert (phi % (2 * math.pi), psi % (2 * math.pi)) == pytest.approx(spin.phases, abs=1e-12)
    assert (theta > math.pi / 2) == spin.anti_aligned
    d = np.linalg.norm(spin.moments * w[0]) ** 2 / np.sum(spin.moments * w[0] ** 2)
    assert (d > spin.moments[1]) == (spin.mode == 'SAM')


def _crossing_times(t, x):
    """Return the times where x crosses 0 upwards, linearly interpolated."""
    k = np.nonzero((x[:-1] < 0.0) & (x[1:] >= 0.0))[0]
    return t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])


def test_periods_are_the_requested(motion):
    """P_psi from w2's upward zero crossings; P_phi from r's azimuth about L, unwrapped."""
    spin, t, w, c = motion
    crossings = _crossing_times(t, w[:, 1])
    p_psi = np.mean(np.diff(crossings)) * 24.0
    assert p_psi == pytest.approx(spin.rotation_period_h, rel=1e-6)
    r_axis = c[:, :, 2] if spin.mode == 'SAM' else c[:, :, 0]
    frame = sc.l_frame(spin.pole_deg)
    azimuth = np.unwrap(np.arctan2(r_axis @ frame[:, 1], r_axis @ frame[:, 0]))
    # over whole periods of psi the mean rate is <phi'>: take the crossings' span
    a, b = np.searchsorted(t, [crossings[0], crossings[-1]])
    rate = (np.interp(crossings[-1], t, azimuth) - np.interp(crossings[0], t, azimuth)) \
        / (crossings[-1] - crossings[0])
    assert a < b
    assert 2 * math.pi / abs(rate) * 24.0 == pytest.approx(spin.precession_period_h, rel=1e-5)


def test_principal_axis_rotator_and_its_lightcurve_period():
    spin = sc.TrueSpin('PA', 5.3, 5.3, (0.5, 0.8), (60.0, 20.0), (1.0, 0.0))
    t = spin.epoch_jd + np.linspace(0.0, 2.0, 301)
    w, c = sc.integrate_attitude(spin, t)
    assert np.allclose(w[:, :2], 0.0, atol=1e-14) and w[:, 2] == pytest.approx(
        2 * math.pi / (5.3 / 24.0), rel=1e-12)
    sun = np.tile([1.0, 0.2, 0.1], (t.size, 1))
    observer = np.tile([0.3, 0.9, -0.1], (t.size, 1))
    axes = sc.ellipsoid_of_inertia(spin.inertia_ratios)

    def lightcurve(shift_h):
        _w, c2 = sc.integrate_attitude(spin, t + shift_h / 24.0)
        return sc.magnitudes(c2, sun, observer, axes, 0.0, 64, 32)

    base = lightcurve(0.0)
    assert np.max(np.abs(lightcurve(5.3 / 2) - base)) < 1e-9    # the ellipsoid's symmetry
    assert np.max(np.abs(lightcurve(5.3 / 4) - base)) > 0.05    # not a quarter period
    assert np.ptp(base) > 0.05


@pytest.mark.parametrize('phase_deg', [0.0, 10.0, 35.0, 70.0, 120.0])
def test_sphere_quadrature_meets_the_closed_form(phase_deg):
    a = math.radians(phase_deg)
    sun = np.array([[0.0, 0.3, 1.0]]) / math.hypot(0.3, 1.0)
    # the observer at angle a from the Sun, turned about an axis normal to the Sun's direction
    axis = np.cross(sun[0], [1.0, 0.0, 0.0])
    axis /= np.linalg.norm(axis)
    observer = (sun[0] * math.cos(a) + np.cross(axis, sun[0]) * math.sin(a))[None, :]
    exact = sc.sphere_brightness(np.array([a]), 1.0)[0]
    errors = [abs(sc.ellipsoid_brightness(sun, observer, (1.0, 1.0, 1.0), 2 * n, n)[0] / exact
                  - 1.0) for n in (32, 128, 512)]
    assert errors[2] < 2e-5
    assert errors[2] < errors[1] < errors[0]
    lommel = sc.ellipsoid_brightness(sun, observer, (1.0, 1.0, 1.0), 1024, 512, lambert=0.0)
    assert lommel[0] == pytest.approx(sc.sphere_brightness(np.array([a]), 1.0, 0.0)[0],
                                      rel=2e-5)


def test_ellipsoid_at_zero_phase_is_half_its_projected_area():
    """Lommel-Seeliger at zero phase: S = mu / 2, so B = (1/2) pi abc |diag(1/a, 1/b, 1/c) d|."""
    axes = np.array([1.0, 0.62, 0.41])
    rng = np.random.default_rng(3)
    d = rng.normal(size=(6, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    exact = 0.5 * math.pi * np.prod(axes) * np.linalg.norm(d / axes, axis=1)
    b = sc.ellipsoid_brightness(d, d, axes, 512, 256, lambert=0.0)
    assert b == pytest.approx(exact, rel=2e-5)


def test_ellipsoid_quadrature_converges():
    axes = sc.ellipsoid_of_inertia((0.55, 0.83))
    rng = np.random.default_rng(4)
    s = rng.normal(size=(20, 3))
    o = s + 0.8 * rng.normal(size=(20, 3))
    s /= np.linalg.norm(s, axis=1)[:, None]
    o /= np.linalg.norm(o, axis=1)[:, None]
    fine = sc.ellipsoid_brightness(s, o, axes, 2048, 1024)
    errors = [np.max(np.abs(sc.ellipsoid_brightness(s, o, axes, 2 * n, n) / fine - 1.0))
              for n in (32, 64, 128)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 2e-4          # the default grid (256 x 128) is finer still


def test_uniform_ellipsoid_has_the_inertia_ratios():
    a, b, c = sc.ellipsoid_of_inertia((0.55, 0.83))
    moments = np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    assert moments / moments[2] == pytest.approx([0.55, 0.83, 1.0], rel=1e-12)


def test_orbits_close_and_light_time():
    period = 2 * math.pi * math.sqrt(sc.EARTH.a ** 3 / sc.GM_SUN)
    jd = np.array([sc.J2000, sc.J2000 + period])
    earth = sc.kepler_position(sc.EARTH, jd)
    assert earth[1] == pytest.approx(earth[0], abs=1e-10)
    assert 0.983 < np.linalg.norm(earth[0]) < 1.017
    assert period == pytest.approx(365.256, abs=0.01)
    received = np.array([2459300.5, 2459310.25])
    t_e, sun, observer = sc._emission_geometry(sc.APOPHIS, received)
    assert received - t_e == pytest.approx(np.linalg.norm(observer, axis=1) / sc.C_AU_PER_DAY,
                                           abs=2e-9)     # JD rounding: 5e-10 d
    assert sun == pytest.approx(-sc.kepler_position(sc.APOPHIS, t_e), abs=1e-15)


def test_campaign_sampling_and_noise():
    spin = sc.TrueSpin('PA', 7.0, 7.0, (0.5, 0.8), (60.0, 20.0), epoch_jd=2459200.5)
    apparition = sc.Apparition(2459169.5, 2459260.5, 25, 500)
    synthetic = sc.make_campaign(spin, [apparition], seed=5, nu=64, nv=32)
    nights = np.unique(synthetic.block)
    assert nights.size == 25 and abs(synthetic.jd.size - 500) <= 3 * 25
    received = synthetic.jd + np.linalg.norm(synthetic.observer, axis=1) / sc.C_AU_PER_DAY
    age = (received - sc.FULL_MOON_JD) % sc.SYNODIC_MONTH
    assert np.all(np.minimum(age, sc.SYNODIC_MONTH - age) > 3.0)
    assert np.all((synthetic.sigma >= 0.01) & (synthetic.sigma <= 0.03))
    campaign = sc.draw(synthetic, np.random.default_rng(6))
    assert campaign.light_time_corrected and all(campaign.free_offset)
    residual = campaign.magnitude - synthetic.model
    # each night: a constant offset plus noise of that night's sigma
    chi2 = sum(np.sum(((residual[synthetic.block == k] - residual[synthetic.block == k].mean())
                       / synthetic.sigma[synthetic.block == k]) ** 2) for k in nights)
    dof = synthetic.jd.size - nights.size
    assert abs(chi2 / dof - 1.0) < 4 * math.sqrt(2.0 / dof)
