"""
Mass models of the body (core/model/mass_models.py) and their files (core/model/shape_files.py).

Proven against closed forms (the ellipsoid's and the box's volume, mass and inertia; the
monomial integrals of the tetrahedron), against an independent quadrature (a product Gauss rule
on the unit ball, mapped onto the ellipsoid, summed with Legendre functions from scipy: the
Stokes coefficients by brute force), by convergence (an icosphere inscribed in an ellipsoid
tends to it at the fitted order 2 in the edge length), and by symmetry (odd degrees vanish for
centrally symmetric bodies). The shape files round trip; bad ones are refused naming the file,
the line and the problem.
"""
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import lpmv, roots_jacobi, roots_legendre

from tumble_ros.core.model.body import BodySpec
from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.core.model.mass_models import (DensityMoments, Ellipsoid, ellipsoid_stokes,
                                               KG_PER_KM3_PER_DENSITY, MassModelError, Polyhedron,
                                               tetrahedron_rule)
from tumble_ros.core.model.shape_files import (box_mesh, ellipsoid_mesh, load_shape, read_mesh,
                                               resolve_shape_path, ShapeFileError, write_counts,
                                               write_obj)

#: The seed of this file's random inputs: each test draws from a generator of its own, so its
#: inputs do not depend on which tests ran before it (pytest-xdist balances them over workers).
SEED = 28
AXES = (0.217, 0.154, 0.147)       # km: an Apophis-like ellipsoid (0.64 : 0.97 : 1)
DENSITY = 2600.0                   # kg/m^3


def rotation(seed):
    """Return a random proper rotation matrix."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def ball_rule(degree):
    """Return (points (n, 3), weights (n,)) on the unit ball, exact to ``degree`` (test's own)."""
    m = degree // 2 + 2
    x, w = roots_jacobi(m, 0.0, 2.0)             # weight (1 + x)^2 on [-1, 1]: r = (1 + x) / 2
    r, wr = (x + 1) / 2, w / 8
    mu, wmu = roots_legendre(m)                  # cos(theta)
    k = degree + 1
    phi, wphi = 2 * np.pi * np.arange(k) / k, np.full(k, 2 * np.pi / k)
    R, MU, PHI = (a.ravel() for a in np.meshgrid(r, mu, phi, indexing='ij'))
    W = np.einsum('i,j,k->ijk', wr, wmu, wphi).ravel()
    s = np.sqrt(1 - MU ** 2)
    return np.column_stack([R * s * np.cos(PHI), R * s * np.sin(PHI), R * MU]), W


def brute_stokes(masses, positions, degree, radius):
    """Return unnormalised (C, S) of point masses by the textbook sum (no Condon-Shortley)."""
    x, y, z = positions.T
    r = np.sqrt(x * x + y * y + z * z)
    sin_lat, lon = z / r, np.arctan2(y, x)
    total = masses.sum()
    C, S = np.zeros((degree + 1, degree + 1)), np.zeros((degree + 1, degree + 1))
    for n in range(degree + 1):
        for m in range(n + 1):
            p = (-1) ** m * lpmv(m, n, sin_lat)
            f = (2 - (m == 0)) * math.factorial(n - m) / math.factorial(n + m)
            common = masses * (r / radius) ** n * p * f / total
            C[n, m] = np.sum(common * np.cos(m * lon))
            S[n, m] = np.sum(common * np.sin(m * lon))
    return C, S


def ellipsoid_point_masses(axes, density, degree):
    """Return the ellipsoid as point masses, exact to ``degree`` (the ball rule, mapped)."""
    points, weights = ball_rule(degree)
    volume = 4 / 3 * np.pi * np.prod(axes)
    masses = weights / weights.sum() * volume * density * KG_PER_KM3_PER_DENSITY
    return masses, points * np.asarray(axes)


def test_the_ball_rule_of_the_tests_is_exact():
    points, weights = ball_rule(6)
    assert weights.sum() == pytest.approx(4 / 3 * np.pi, rel=1e-14)
    # integral of x^2 y^2 z^2 over the unit ball = 4 pi / 945 ... and of z^4 = 4 pi / 35
    x, y, z = points.T
    assert np.sum(weights * z ** 4) == pytest.approx(4 * np.pi / 35, rel=1e-13)
    assert np.sum(weights * x ** 2 * y ** 2 * z ** 2) == pytest.approx(4 * np.pi / 945, rel=1e-13)


# -- Quadrature on a tetrahedron ---------------------------------------------------------------

@pytest.mark.parametrize('degree', [0, 1, 2, 3, 4, 5, 8])
def test_the_tetrahedron_rule_integrates_every_monomial_of_its_degree_exactly(degree):
    bary, weights = tetrahedron_rule(degree)
    assert np.all(weights > 0)
    u, v, w = bary.T
    for i in range(degree + 1):
        for j in range(degree + 1 - i):
            for k in range(degree + 1 - i - j):
                exact = (math.factorial(i) * math.factorial(j) * math.factorial(k)
                         / math.factorial(i + j + k + 3)) * 6     # over the volume 1/6
                integral = np.sum(weights * u ** i * v ** j * w ** k)
                assert integral == pytest.approx(exact, rel=1e-12)


def test_the_tetrahedron_rule_is_not_exact_beyond_its_degree():
    bary, weights = tetrahedron_rule(2)        # 2 points a coordinate: exact to degree 3 only
    u = bary[:, 0]
    exact = math.factorial(4) / math.factorial(7) * 6
    assert abs(np.sum(weights * u ** 4) - exact) > 1e-6 * exact


# -- Ellipsoid ---------------------------------------------------------------------------------

def test_the_ellipsoid_mass_volume_and_inertia_are_the_closed_forms():
    a, b, c = AXES
    body = Ellipsoid(AXES, DENSITY)
    volume = 4 / 3 * np.pi * a * b * c
    assert body.volume == pytest.approx(volume, rel=1e-15)
    assert body.mass == pytest.approx(DENSITY * volume * 1e9, rel=1e-15)
    # Apophis-sized: ~5e10 kg (0.34 km mean diameter at 2.6 g/cm^3 is 5.35e10 kg)
    assert 4e10 < body.mass < 7e10
    np.testing.assert_allclose(body.principal_moments,
                               body.mass / 5 * np.array([b * b + c * c, a * a + c * c,
                                                         a * a + b * b]), rtol=1e-15)
    # independently: the ball rule mapped onto the ellipsoid, sum of m (r^2 - x x)
    masses, points = ellipsoid_point_masses(AXES, DENSITY, 2)
    second = np.einsum('k,ki,kj->ij', masses, points, points)
    brute = np.trace(second) * np.eye(3) - second
    np.testing.assert_allclose(body.inertia_tensor, brute, rtol=1e-13, atol=1e-13 * brute.max())
    assert masses.sum() == pytest.approx(body.mass, rel=1e-14)


def test_the_ellipsoid_inertia_ratios_are_apophis():
    moments = Ellipsoid(AXES, DENSITY).principal_moments
    np.testing.assert_allclose(moments / moments[2], [0.64, 0.97, 1.0], atol=0.01)


def test_the_ellipsoid_stokes_closed_form_matches_brute_force_to_degree_8():
    degree, radius = 8, 0.25
    C, S = ellipsoid_stokes(AXES, degree, radius)
    masses, points = ellipsoid_point_masses(AXES, DENSITY, degree)
    Cb, Sb = brute_stokes(masses, points, degree, radius)
    np.testing.assert_allclose(C, Cb, rtol=0, atol=1e-14)
    np.testing.assert_allclose(S, Sb, rtol=0, atol=1e-14)
    a, b, c = AXES
    assert C[2, 0] == pytest.approx((2 * c * c - a * a - b * b) / (10 * radius ** 2), rel=1e-14)
    assert C[2, 2] == pytest.approx((a * a - b * b) / (20 * radius ** 2), rel=1e-14)
    assert abs(C[4, 0]) > 1e-4 and abs(C[4, 4]) > 1e-7 and abs(C[8, 8]) > 0  # (tested, not 0)
    # degree 2 from the inertia: C20 = (A + B - 2C) / (2 M R^2), C22 = (B - A) / (4 M R^2)
    body = Ellipsoid(AXES, DENSITY)
    A, B, Cm = body.principal_moments
    assert C[2, 0] == pytest.approx((A + B - 2 * Cm) / (2 * body.mass * radius ** 2), rel=1e-13)
    assert C[2, 2] == pytest.approx((B - A) / (4 * body.mass * radius ** 2), rel=1e-13)


def test_the_ellipsoid_odd_degrees_and_sine_terms_vanish():
    C, S = ellipsoid_stokes(AXES, 7, 0.3)
    assert np.all(C[1::2] == 0) and np.all(S == 0) and np.all(C[:, 1::2] == 0)


@pytest.mark.parametrize('field, value', [
    ('semi_axes', (1.0, 0.0, 1.0)), ('semi_axes', (1.0, 2.0)), ('semi_axes', (1, 1, 'x')),
    ('density', -1.0), ('density', 2.6), ('density', float('nan'))])
def test_a_bad_ellipsoid_is_refused_naming_its_field(field, value):
    values = {'semi_axes': AXES, 'density': DENSITY, field: value}
    with pytest.raises(ScenarioError, match=f'^{field}'):
        Ellipsoid(values['semi_axes'], values['density'])


# -- Polyhedra ---------------------------------------------------------------------------------

def test_a_box_has_the_closed_form_volume_centre_and_inertia():
    a, b, c = 0.3, 0.2, 0.1
    body = Polyhedron(*box_mesh((a, b, c)), DENSITY)
    mass = DENSITY * 8 * a * b * c * 1e9
    assert body.volume == pytest.approx(8 * a * b * c, rel=1e-14)
    assert body.mass == pytest.approx(mass, rel=1e-14)
    np.testing.assert_allclose(body.centre_of_mass, 0, atol=1e-15)
    np.testing.assert_allclose(body.inertia_tensor,
                               np.diag(mass / 3 * np.array([b * b + c * c, a * a + c * c,
                                                            a * a + b * b])),
                               rtol=1e-14, atol=1e-14 * mass * a * a)
    assert body.convex and body.is_principal


def test_a_tilted_shifted_box_has_the_parallel_axis_inertia():
    a, b, c = 0.3, 0.2, 0.1
    v, f = box_mesh((a, b, c))
    R, shift = rotation(1), np.array([1.0, -2.0, 0.5])
    body = Polyhedron(v @ R.T + shift, f, DENSITY)
    mass = body.mass
    moments = mass / 3 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    expected = R @ np.diag(moments) @ R.T
    np.testing.assert_allclose(body.centre_of_mass, shift, atol=1e-14)
    np.testing.assert_allclose(body.inertia_tensor, expected, atol=1e-12 * np.abs(expected).max())


def convergence_order(errors, facets):
    """Fit the order p of error ~ h^p, h ~ facets^(-1/2)."""
    h = np.asarray(facets, dtype=float) ** -0.5
    return np.polyfit(np.log(h), np.log(np.abs(errors)), 1)[0]


def test_an_icosphere_converges_to_the_ellipsoid_at_order_two():
    ellipsoid = Ellipsoid(AXES, DENSITY)
    facets, volume, inertia = [], [], []
    for k in range(2, 6):
        body = Polyhedron(*ellipsoid_mesh(AXES, k), DENSITY)
        facets.append(len(body.facets))
        volume.append(body.volume / ellipsoid.volume - 1)
        inertia.append(np.max(np.abs(body.principal_moments / ellipsoid.principal_moments - 1)))
    assert abs(volume[-1]) < 1e-3 and inertia[-1] < 2e-3
    assert convergence_order(volume, facets) == pytest.approx(2.0, abs=0.1)
    assert convergence_order(inertia, facets) == pytest.approx(2.0, abs=0.1)


def test_the_point_masses_of_a_nonconvex_body_carry_its_mass_centre_and_inertia():
    rng = np.random.default_rng(SEED)
    v, f = ellipsoid_mesh((0.3, 0.2, 0.15), 2)
    v = v * rng.uniform(0.7, 1.1, size=(len(v), 1))        # a lumpy, star-shaped body
    v[0] *= 0.4                                            # a deep dent: not convex
    body = Polyhedron(v @ rotation(2).T + [0.1, 0.0, -0.2], f, DENSITY)
    assert not body.convex
    masses, points = body.point_masses(2)
    assert masses.sum() == pytest.approx(body.mass, rel=1e-13)
    np.testing.assert_allclose(masses @ points, 0, atol=1e-13 * body.mass)
    second = np.einsum('k,ki,kj->ij', masses, points, points)
    brute = np.trace(second) * np.eye(3) - second
    np.testing.assert_allclose(brute, np.diag(body.principal_moments),
                               atol=1e-12 * body.principal_moments.max())
    assert np.all(np.diff(body.principal_moments) > 0)


def test_a_shifted_rotated_shape_is_recentred_into_principal_axes():
    v, f = ellipsoid_mesh(AXES, 3)
    R, shift = rotation(3), np.array([0.5, -1.0, 2.0])
    moved = Polyhedron(v @ R.T + shift, f, DENSITY)
    assert not moved.is_principal
    body = moved.in_principal_axes()
    assert body.is_principal
    np.testing.assert_allclose(body.reference.offset, shift, atol=1e-13)
    # the rotation's rows are the body's axes in the file: R's columns, up to their sign
    signs = np.sign(np.einsum('ij,ji->i', np.asarray(body.reference.rotation), R))
    np.testing.assert_allclose(np.asarray(body.reference.rotation), (R * signs).T, atol=1e-12)
    assert np.prod(signs) == 1
    np.testing.assert_allclose(body.vertices, v * signs, atol=1e-13)
    np.testing.assert_allclose(body.centre_of_mass, 0, atol=1e-15)
    np.testing.assert_allclose(body.inertia_tensor, np.diag(body.principal_moments),
                               atol=1e-13 * body.principal_moments.max())
    # the reference maps the file's points onto the principal frame's
    np.testing.assert_allclose(body.reference.apply(moved.vertices), body.vertices, atol=1e-13)
    assert body.volume == pytest.approx(moved.volume, rel=1e-13)


@pytest.mark.parametrize('axes', [(0.3, 0.2, 0.1), (0.1, 0.3, 0.2)])
def test_the_principal_axes_are_ordered_by_increasing_moment(axes):
    body = Polyhedron(*box_mesh(axes), DENSITY).in_principal_axes()
    assert np.all(np.diff(body.principal_moments) > 0)
    extent = np.ptp(body.vertices, axis=0)
    assert np.all(np.diff(extent) < 0)                        # x the longest: least inertia


def test_a_box_polyhedron_has_no_odd_degree_moments():
    body = Polyhedron(*box_mesh((0.3, 0.2, 0.1)), DENSITY)
    masses, points = body.point_masses(7)
    C, S = brute_stokes(masses, points, 7, 0.4)
    assert np.max(np.abs(C[1::2])) < 1e-15 and np.max(np.abs(S)) < 1e-15
    assert abs(C[2, 0]) > 0.05 and abs(C[4, 0]) > 1e-3
    field = body.gravity_field(7, 0.4)
    np.testing.assert_allclose(field.C, C, rtol=0, atol=1e-15)
    assert np.max(np.abs(field.C[1::2])) < 1e-15 and np.max(np.abs(field.S)) < 1e-15
    cube = Polyhedron(*box_mesh((0.2, 0.2, 0.2)), DENSITY)      # equal moments: axes kept
    assert cube.is_principal and cube.gravity_field(4).C[2, 0] == pytest.approx(0, abs=1e-15)


def test_an_icosphere_converges_to_the_ellipsoid_stokes_coefficients():
    degree, radius = 6, 0.25
    exact, _ = ellipsoid_stokes(AXES, degree, radius)
    facets, errors = [], []
    for k in range(2, 5):
        body = Polyhedron(*ellipsoid_mesh(AXES, k), DENSITY)
        masses, points = body.point_masses(degree)
        C, S = brute_stokes(masses, points, degree, radius)
        facets.append(len(body.facets))
        errors.append([abs(C[n, m] / exact[n, m] - 1)
                       for n, m in [(2, 0), (2, 2), (4, 0), (4, 2), (4, 4), (6, 0)]])
        assert np.max(np.abs(C[1::2])) < 1e-15 * radius and np.max(np.abs(S)) < 1e-14
    errors = np.array(errors)
    assert np.all(errors[-1] < 0.02)
    for column in errors.T:
        assert convergence_order(column, facets) == pytest.approx(2.0, abs=0.15)


# -- Validation of a mesh ----------------------------------------------------------------------

def test_a_mesh_with_a_missing_facet_is_refused_as_open():
    v, f = box_mesh((1, 1, 1))
    with pytest.raises(MassModelError, match='facets.*no facet on its other side.*open'):
        Polyhedron(v, f[:-1], DENSITY)


def test_a_mesh_with_one_flipped_facet_is_refused_as_inconsistent():
    v, f = box_mesh((1, 1, 1))
    f = f.copy()
    f[5] = f[5, ::-1]
    with pytest.raises(MassModelError, match='not consistently oriented') as info:
        Polyhedron(v, f, DENSITY)
    assert info.value.facet == 5 or 5 in (info.value.facet,) or 'facets[5]' in str(info.value)


def test_an_inverted_mesh_is_refused():
    v, f = box_mesh((1, 1, 1))
    with pytest.raises(MassModelError, match='oriented inward'):
        Polyhedron(v, f[:, ::-1], DENSITY)


def test_a_flat_mesh_is_refused_as_zero_volume():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])   # a tetrahedron, squashed
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    with pytest.raises(MassModelError, match='zero volume'):
        Polyhedron(v, f, DENSITY)


def test_an_out_of_range_vertex_index_is_refused():
    v, f = box_mesh((1, 1, 1))
    f = f.copy()
    f[3, 1] = 8
    with pytest.raises(MassModelError, match=r'facets\[3\]: vertex index outside \[0, 7\]'):
        Polyhedron(v, f, DENSITY)


# -- Shape files -------------------------------------------------------------------------------

def test_obj_and_counts_files_of_the_same_body_give_the_same_model(tmp_path):
    v, f = ellipsoid_mesh(AXES, 2)
    v = v @ rotation(4).T + [0.01, 0.02, -0.03]
    write_obj(tmp_path / 'body.obj', v, f, comment='test body')
    write_counts(tmp_path / 'body.tab', v, f)
    one = load_shape(tmp_path / 'body.obj', DENSITY)
    two = load_shape(tmp_path / 'body.tab', DENSITY)
    reference = Polyhedron(v, f, DENSITY)
    for body in (one, two):
        np.testing.assert_array_equal(body.facets, f)
        np.testing.assert_allclose(body.vertices, v, rtol=1e-11)
        assert body.volume == pytest.approx(reference.volume, rel=1e-10)
        np.testing.assert_allclose(body.inertia_tensor, reference.inertia_tensor,
                                   rtol=1e-9, atol=1e-10 * reference.principal_moments.max())


def test_an_obj_file_with_texture_normals_quads_and_negative_indices_is_read(tmp_path):
    text = """# a unit cube, quads, with vt/vn and relative indices
o cube
mtllib none.mtl
v -1 -1 -1
v -1 -1 1
v -1 1 -1
v -1 1 1
v 1 -1 -1
v 1 -1 1
v 1 1 -1
v 1 1 1
vt 0 0
vn 0 0 1
s off
f 1/1/1 2/1/1 4/1/1 3/1/1
f 5//1 7//1 8//1 6//1
f 1 5 6 2
f -6 -5 -1 -2
f 1 3 7 5
f 2 6 8 4
"""
    (tmp_path / 'cube.obj').write_text(text)
    body = load_shape(tmp_path / 'cube.obj', 1000.0)
    assert len(body.facets) == 12
    assert body.volume == pytest.approx(8.0, rel=1e-15)
    assert body.mass == pytest.approx(8e12, rel=1e-15)


def test_a_counts_file_with_row_numbers_is_read(tmp_path):
    v, f = box_mesh((1, 2, 3))
    lines = [f'{len(v)} {len(f)}'] + [f'{k + 1} {x} {y} {z}' for k, (x, y, z) in enumerate(v)]
    lines += [f'{k + 1} {i + 1} {j + 1} {m + 1}' for k, (i, j, m) in enumerate(f)]
    (tmp_path / 'box.txt').write_text('\n'.join(lines) + '\n')
    assert load_shape(tmp_path / 'box.txt', 1000.0).volume == pytest.approx(48.0, rel=1e-15)


def obj_lines(v, f):
    """Return the OBJ lines of a mesh (facets 0-based in, 1-based out)."""
    return ([f'v {x} {y} {z}' for x, y, z in v]
            + [f'f {i + 1} {j + 1} {k + 1}' for i, j, k in f])


@pytest.mark.parametrize('edit, message', [
    (lambda L: L[:8] + ['f 1 2 99'] + L[9:], r'line 9: facet vertex 99 does not exist'),
    (lambda L: L[:-1], r'line \d+: .*no facet on its other side'),
    (lambda L: L[:8] + ['f 1 4 2'] + L[9:], r'line (9|\d+): .*not consistently oriented'),
    (lambda L: L[:8] + [' '.join(['f'] + line.split()[1:][::-1]) for line in L[8:]],
     r'oriented inward'),
    (lambda L: L[:3] + ['v 1 2 x'] + L[4:], r'line 4: vertex: .* are not numbers'),
    (lambda L: L[:3] + ['v 1 2'] + L[4:], r'line 4: a vertex needs x y z'),
    (lambda L: [], r'holds no vertices'),
])
def test_a_bad_obj_file_is_refused_naming_file_line_and_problem(tmp_path, edit, message):
    v, f = box_mesh((1, 1, 1))
    path = tmp_path / 'bad.obj'
    path.write_text('\n'.join(edit(obj_lines(v, f))) + '\n')
    with pytest.raises(ShapeFileError, match=f'^shape_file: {path}.*{message}'):
        load_shape(path, DENSITY)


def test_a_flat_obj_file_is_refused_as_zero_volume(tmp_path):
    path = tmp_path / 'flat.obj'
    path.write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n')
    with pytest.raises(ShapeFileError, match='flat.obj: facets: enclose zero volume'):
        load_shape(path, DENSITY)


@pytest.mark.parametrize('text, message', [
    ('8 12\n0 0 0\n', 'announces 8 vertices and 12 facets, the file holds 1 data lines'),
    ('4 4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 3 2\n1 2 4\n1 4 3\n2 3 5\n',
     'line 9: facet 4: vertex 5 does not exist'),
    ('4 4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 3 2\n1 2 4\n1 4 3\n2 3 4\n9 9 9\n',
     'line 10: data after the 4 vertices'),
    ('4 4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 3 2\n1 2 4\n1 4 3\n2 4 3\n',
     r'line 9: facets\[3\]: edge'),
])
def test_a_bad_counts_file_is_refused_naming_file_line_and_problem(tmp_path, text, message):
    path = tmp_path / 'bad.tab'
    path.write_text(text)
    with pytest.raises(ShapeFileError, match=message):
        load_shape(path, DENSITY)


def test_a_tetrahedron_in_the_counts_format_has_its_closed_form_volume(tmp_path):
    path = tmp_path / 'tet.tab'
    path.write_text('4 4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 3 2\n1 2 4\n1 4 3\n2 3 4\n')
    body = load_shape(path, 1000.0)
    assert body.volume == pytest.approx(1 / 6, rel=1e-15)
    np.testing.assert_allclose(body.centre_of_mass, [0.25] * 3, rtol=1e-15)


def test_a_missing_shape_file_is_named():
    with pytest.raises(ShapeFileError, match='nowhere.obj: no such file'):
        read_mesh('/nowhere.obj')


def test_shape_paths_resolve_absolute_then_params_file_then_package(tmp_path):
    (tmp_path / 'shapes').mkdir()
    local = tmp_path / 'shapes' / 'mine.obj'
    local.write_text('')
    params = tmp_path / 'run.yaml'
    assert resolve_shape_path(local) == local
    assert resolve_shape_path('shapes/mine.obj', params) == local
    shipped = resolve_shape_path('config/shapes/apophis.obj', params)
    assert shipped.name == 'apophis.obj' and shipped.is_file()
    with pytest.raises(ShapeFileError, match="'shapes/none.obj' not found; tried .*shapes"):
        resolve_shape_path('shapes/none.obj', params)
    with pytest.raises(ShapeFileError, match='does not exist'):
        resolve_shape_path(tmp_path / 'none.obj')


@pytest.mark.parametrize('name', ['apophis.obj', 'apophis_radar.tab'])
def test_the_shipped_apophis_shape_has_the_cited_inertia_ratios_and_size(name):
    body = load_shape(resolve_shape_path(f'config/shapes/{name}'), DENSITY)
    assert len(body.facets) == 320 and body.convex and body.is_principal
    moments = body.principal_moments
    np.testing.assert_allclose(moments / moments[2], [0.64, 0.97, 1.0], atol=1e-6)
    assert (6 * body.volume / np.pi) ** (1 / 3) == pytest.approx(0.34, rel=1e-6)
    other = load_shape(resolve_shape_path('config/shapes/apophis.obj'), DENSITY)
    np.testing.assert_allclose(body.vertices, other.vertices, rtol=1e-12)


# -- Density moments given directly, and the body.* parameters ---------------------------------

def apophis_moments(**changes):
    """Return DensityMoments parameters of the Apophis-like ellipsoid to degree 4."""
    body = Ellipsoid(AXES, DENSITY)
    C, S = body.stokes(4, 0.25)
    stokes = [v for n in range(1, 5) for m in range(n + 1)
              for v in (n, m, C[n, m], S[n, m])]
    params = {'mass': body.mass, 'reference_radius': 0.25, 'stokes': stokes,
              'principal_moments': tuple(body.principal_moments)}
    params.update(changes)
    return params


def test_density_moments_of_an_ellipsoid_are_accepted_with_its_moments():
    moments = DensityMoments.from_parameters(apophis_moments())
    body = Ellipsoid(AXES, DENSITY)
    np.testing.assert_array_equal(moments.field.C, body.stokes(4, 0.25)[0])
    np.testing.assert_allclose(moments.principal_moments, body.principal_moments, rtol=1e-15)
    assert moments.field.degree == 4 and moments.field.C[0, 0] == 1.0
    assert moments.gravity_field(4) == body.gravity_field(4, 0.25)
    assert moments.gravity_field(2) == body.gravity_field(2, 0.25)
    longer = moments.gravity_field(6)
    np.testing.assert_array_equal(longer.C[5:], 0)
    np.testing.assert_array_equal(longer.C[:5, :5], moments.field.C)


@pytest.mark.parametrize('changes, message', [
    ({'stokes': [2, 0, -0.05, 0.0]}, r'stokes C\[2, 0\]: must agree with principal_moments'),
    ({'stokes': [1, 1, 1e-3, 0.0]}, r'stokes C\[1, 1\]: must be 0 .*centre-of-mass principal'),
    ({'stokes': [2, 1, 0.0, 1e-3]}, r'stokes S\[2, 1\]: must be 0'),
    ({'stokes': [2, 0, 0.0]}, 'stokes: must be a flat list of'),
    ({'stokes': [2, 3, 0.0, 0.0]}, r'stokes\[0:2\]: must be integers'),
    ({'principal_moments': (1.0, 1.0, 3.0), 'mass': 1.0, 'reference_radius': 1.0,
      'stokes': [2, 0, -2.0, 0.0]}, 'principal_moments: each must be <= the sum'),
    ({'mass': -1.0}, 'mass: must be a finite number > 0'),
])
def test_density_moments_that_disagree_are_refused(changes, message):
    with pytest.raises(MassModelError, match=message):
        DensityMoments.from_parameters(apophis_moments(**changes))


def test_a_body_spec_derives_the_normalised_inertia_from_its_model():
    spec = BodySpec.from_parameters({'body.model': 'ellipsoid', 'body.semi_axes': list(AXES),
                                     'body.density': 2600})
    a2, b2, c2 = (s * s for s in AXES)
    expected = np.array([b2 + c2, a2 + c2, a2 + b2]) / (a2 + b2)
    np.testing.assert_allclose(spec.inertia, expected, rtol=1e-15)
    assert spec.density == 2600.0 and isinstance(spec.density, float)
    assert BodySpec.from_parameters(spec.to_parameters()) == spec
    assert BodySpec().inertia is None and BodySpec().mass_model is None


def test_a_body_spec_reads_the_shipped_shape_into_principal_axes(tmp_path):
    spec = BodySpec.from_parameters({'body.model': 'polyhedron', 'body.density': 2600,
                                     'body.shape_file': 'config/shapes/apophis_radar.tab'})
    assert Path(spec.shape_file).is_absolute()
    np.testing.assert_allclose(spec.inertia, [0.64, 0.97, 1.0], atol=1e-9)
    # a shifted copy beside a params file: read relative to it, moved back, the move recorded
    v = spec.mass_model.vertices
    write_obj(tmp_path / 'moved.obj', v + [1.0, 2.0, 3.0], spec.mass_model.facets)
    moved = BodySpec.from_parameters({'body.model': 'polyhedron', 'body.density': 2600,
                                      'body.shape_file': 'moved.obj'}, tmp_path / 'run.yaml')
    np.testing.assert_allclose(moved.mass_model.reference.offset, [1.0, 2.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(moved.inertia, spec.inertia, rtol=1e-10)  # (12 digits written)


@pytest.mark.parametrize('params, message', [
    ({'body.model': 'blob'}, 'body.model: must be one of'),
    ({'body.model': 'ellipsoid', 'body.semi_axes': [1, 1, 1], 'body.density': 2600,
      'body.shape_file': 'x.obj'}, 'body.shape_file: is not used by body.model ellipsoid'),
    ({'body.model': 'inertia', 'body.density': 2600}, 'body.density: is not used by'),
    ({'body.model': 'polyhedron', 'body.density': 2600}, 'body.shape_file: .*needs one'),
    ({'body.model': 'polyhedron', 'body.density': 2600, 'body.shape_file': 'no.obj'},
     "body.shape_file: 'no.obj' not found"),
    ({'body.model': 'ellipsoid', 'body.semi_axes': [1, 1, 1], 'body.density': 2.6},
     r'body.density: must be in \[100, 30000\] kg/m\^3'),
    ({'body.model': 'ellipsoid', 'body.semi_axes': [1, 1, 1], 'body.color': 'red'},
     'body.color: unknown body parameter'),
])
def test_bad_body_parameters_are_refused_naming_the_parameter(params, message):
    with pytest.raises(ScenarioError, match=message):
        BodySpec.from_parameters(params)


# -- Gravity fields (GravityField, core/model/gravity_field.py) --------------------------------

def lumpy_body(seed=5):
    """Return a lumpy, dented (non-convex), tilted and shifted polyhedron."""
    rng = np.random.default_rng(seed)
    v, f = ellipsoid_mesh((0.3, 0.2, 0.15), 2)
    v = v * rng.uniform(0.7, 1.1, size=(len(v), 1))
    v[0] *= 0.4
    return Polyhedron(v @ rotation(seed).T + [0.1, 0.0, -0.2], f, DENSITY)


def test_the_polyhedron_field_is_the_brute_force_sum_of_its_point_masses():
    body = lumpy_body()
    field = body.gravity_field(6, 0.4)
    masses, points = body.point_masses(6)
    C, S = brute_stokes(masses, points, 6, 0.4)
    np.testing.assert_allclose(field.C, C, rtol=0, atol=1e-14)
    np.testing.assert_allclose(field.S, S, rtol=0, atol=1e-14)
    assert field.mass == pytest.approx(body.mass, rel=1e-15)
    np.testing.assert_allclose(field.principal_moments, body.principal_moments, rtol=1e-14)
    assert np.max(np.abs(C[3:])) > 1e-4                  # an asymmetric body: odd terms too


def test_the_polyhedron_field_does_not_depend_on_where_the_tetrahedra_meet():
    """Exact quadrature: an apex far outside (a quarter of the masses negative) changes nothing."""
    centred = lumpy_body().in_principal_axes()
    inside = brute_stokes(*centred.point_masses(8), 8, 0.4)
    masses, points = centred.point_masses(8, apex=[2.0, -1.0, 0.5])
    assert np.sum(masses < 0) > len(masses) / 4
    outside = brute_stokes(masses, points, 8, 0.4)
    np.testing.assert_allclose(outside[0], inside[0], rtol=0, atol=1e-11)
    np.testing.assert_allclose(outside[1], inside[1], rtol=0, atol=1e-11)


def test_the_ellipsoid_field_is_its_closed_form_and_checked_by_gravity_field():
    body = Ellipsoid(AXES, DENSITY)
    field = body.gravity_field(6)
    assert field.reference_radius == max(AXES) and field.mass == body.mass
    np.testing.assert_array_equal(field.C, ellipsoid_stokes(AXES, 6, max(AXES))[0])
    np.testing.assert_allclose(field.principal_moments, body.principal_moments, rtol=1e-15)


def test_an_icosphere_field_converges_to_the_ellipsoid_field():
    exact = Ellipsoid(AXES, DENSITY).gravity_field(4, 0.25)
    errors = []
    for k in (2, 3, 4):
        field = Polyhedron(*ellipsoid_mesh(AXES, k), DENSITY).gravity_field(4, 0.25)
        errors.append(np.max(np.abs(field.C - exact.C) / np.maximum(np.abs(exact.C), 1e-300)
                             * (exact.C != 0)))
        assert np.max(np.abs(field.C[1::2])) < 1e-15 and np.max(np.abs(field.S)) < 1e-15
    assert errors[-1] < 0.02
    assert convergence_order(errors, [320, 1280, 5120]) == pytest.approx(2.0, abs=0.15)


# -- The scenario's body.* parameters ----------------------------------------------------------

CONFIG = Path(__file__).resolve().parents[1] / 'config'


def apophis_params(**changes):
    """Return the flat parameters of config/apophis_2029.yaml with ``changes``."""
    from tumble_ros.core import load_scenario
    params = load_scenario(CONFIG / 'apophis_2029.yaml').to_parameters()
    params.update(changes)
    return params


def test_a_scenario_derives_its_inertia_and_field_from_the_shipped_shape():
    from tumble_ros.core import Scenario
    params = apophis_params(**{'body.model': 'polyhedron', 'body.density': 2600.0,
                               'body.shape_file': 'config/shapes/apophis.obj',
                               'gravity.degree': 4})
    scenario = Scenario.from_parameters(params)        # its inertia 0.64 : 0.97 : 1 agrees
    shape = load_shape(resolve_shape_path('config/shapes/apophis.obj'), 2600.0)
    np.testing.assert_allclose(scenario.inertia, shape.principal_moments
                               / shape.principal_moments.max(), rtol=1e-15)
    assert scenario.gravity_field == shape.gravity_field(4)
    assert scenario.gravity_field.degree == 4
    again = Scenario.from_parameters(scenario.to_parameters())
    assert again == scenario


def test_a_scenario_refuses_an_inertia_that_disagrees_with_its_mass_model():
    from tumble_ros.core import Scenario
    body = {'body.model': 'ellipsoid', 'body.semi_axes': [0.3, 0.2, 0.1], 'body.density': 2000}
    with pytest.raises(ScenarioError, match=r'^inertia: disagrees with the mass model \(body.'
                                            r'model ellipsoid\).*got \[0.64, 0.97, 1.0\]'):
        Scenario.from_parameters(apophis_params(**body))
    # the default counts as not given (a node's parameters always hold it): derived
    assert Scenario.from_parameters({'inertia': [1.0, 1.0, 1.5], **body}) == (
        Scenario.from_parameters(body))
    scenario = Scenario.from_parameters(body)             # no inertia given: derived
    a2, b2, c2 = 0.09, 0.04, 0.01
    np.testing.assert_allclose(scenario.inertia, np.array([b2 + c2, a2 + c2, a2 + b2]) / 0.13,
                               rtol=1e-15)
    with pytest.raises(ScenarioError, match='inertia: disagrees'):
        scenario.replace(inertia=(1.0, 2.0, 2.5))


def test_the_papers_normalised_inertia_scenarios_are_unchanged():
    from tumble_ros.core import load_scenario, Scenario
    for name in ('default.yaml', 'fig4.yaml', 'fig6.yaml', 'apophis_2029.yaml'):
        scenario = load_scenario(CONFIG / name)
        assert scenario.body == BodySpec() and scenario.body.mass_model is None
        assert scenario.gravity_field is None
    assert Scenario().inertia == (1.0, 1.0, 1.5)
    assert Scenario().to_parameters()['body.model'] == 'inertia'


def test_a_params_file_names_its_shape_relative_to_itself(tmp_path):
    from tumble_ros.core import load_scenario
    v, f = ellipsoid_mesh((0.3, 0.2, 0.1), 2)
    (tmp_path / 'shapes').mkdir()
    write_counts(tmp_path / 'shapes' / 'body.tab', v + [5.0, 0.0, 0.0], f)
    (tmp_path / 'run.yaml').write_text(
        '/**/sim:\n  ros__parameters:\n    body:\n      model: polyhedron\n'
        '      shape_file: shapes/body.tab\n      density: 1500.0\n')
    scenario = load_scenario(tmp_path / 'run.yaml')
    assert scenario.body.shape_file == str(tmp_path / 'shapes' / 'body.tab')
    np.testing.assert_allclose(scenario.body.mass_model.reference.offset, [5.0, 0, 0],
                               atol=1e-12)
    body = Polyhedron(v, f, 1500.0)
    np.testing.assert_allclose(scenario.inertia, body.principal_moments
                               / body.principal_moments.max(), rtol=1e-10)  # (12 digits)
    (tmp_path / 'bad.yaml').write_text(
        '/**/sim:\n  ros__parameters:\n    body:\n      model: polyhedron\n'
        '      shape_file: shapes/none.tab\n      density: 1500.0\n')
    with pytest.raises(ScenarioError, match="bad.yaml: body.shape_file: 'shapes/none.tab' not "
                                            'found'):
        load_scenario(tmp_path / 'bad.yaml')


# -- bounded and checked: issue 48 ---------------------------------------------------------------

def brute_convexity(v, f, tolerance):
    """Tell convexity by the definition, O(F V): no vertex above any facet's plane."""
    a = v[f[:, 0]]
    n = np.cross(v[f[:, 1]] - a, v[f[:, 2]] - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    height = v @ n.T - np.einsum('ij,ij->i', a, n)
    return height.max() <= tolerance * np.ptp(v, axis=0).max()


@pytest.mark.parametrize('depth', [0.0, 1e-9, 1e-3, 0.05, 0.5, -0.3])
def test_the_edge_convexity_check_agrees_with_every_vertex_against_every_facet(depth):
    """Icospheres with vertices pushed in (a dent) or out (a spike): the two checks agree."""
    from tumble_ros.core.model.mesh_checks import convexity_defect, CONVEXITY_TOLERANCE
    rng = np.random.default_rng(SEED)
    v, f = ellipsoid_mesh(AXES, 3)
    for _ in range(4):
        moved = v.copy()
        moved[rng.integers(len(v), size=3)] *= 1.0 - depth
        expected = brute_convexity(moved, f, CONVEXITY_TOLERANCE)
        assert (convexity_defect(moved, f) is None) == expected
        assert Polyhedron(moved, f, DENSITY).convex == expected
    assert expected == (depth in (0.0, 1e-9, 1e-3))  # (1e-3: within the facets' own bulge)


def test_a_surface_with_a_saddle_vertex_is_not_convex():
    """A box whose face centre is raised into a tent is convex; lowered into a pit, it is not."""
    from tumble_ros.core.model.mesh_checks import convexity_defect
    v, f = box_mesh((1.0, 1.0, 1.0))
    top = [k for k, facet in enumerate(f) if np.all(v[facet][:, 2] > 0)]
    rest = np.delete(f, top, axis=0)
    corners = [1, 5, 7, 3]                           # the top face (z = 1), counter-clockwise
    for height, convex in ((1.2, True), (0.8, False)):
        apex = np.vstack([v, [0.0, 0.0, height]])
        tent = [[corners[k], corners[(k + 1) % 4], 8] for k in range(4)]
        facets = np.vstack([rest, tent])
        assert (convexity_defect(apex, facets) is None) == convex
        assert Polyhedron(apex, facets, DENSITY).convex == convex


def test_convex_mesh_refuses_an_open_surface_and_two_bodies():
    from tumble_ros.core.photometry import convex_mesh
    v, f = box_mesh((1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match='shared by 1 facet.*not a closed surface'):
        convex_mesh(v, f[1:])
    with pytest.raises(ValueError, match='2 separate bodies'):
        convex_mesh(np.vstack([v, v + 3.0]), np.vstack([f, f + len(v)]))


def test_a_shape_file_above_the_facet_limit_is_refused_at_the_line_that_passes_it(
        tmp_path, monkeypatch):
    """The reader stops at the first facet or vertex beyond MAX_FACETS, naming its line."""
    import tumble_ros.core.model.shape_files as shape_files
    monkeypatch.setattr(shape_files, 'MAX_FACETS', 12)
    v, f = ellipsoid_mesh(AXES, 1)                  # 42 vertices, 80 facets
    write_obj(tmp_path / 'many.obj', v, f)
    with pytest.raises(ShapeFileError, match=r'many.obj: more than 12 facets '
                       r"\(MAX_FACETS.*80 'f' lines"):       # counted before the lines are read
        read_mesh(tmp_path / 'many.obj')
    write_obj(tmp_path / 'vertices.obj', v, f[:12])
    with pytest.raises(ShapeFileError,
                       match=r"vertices.obj: more than 12 vertices .*42 'v' lines"):
        read_mesh(tmp_path / 'vertices.obj')
    # six hexagons: 6 lines, 24 triangles, refused at the line whose fan passes the limit
    hexagons = ''.join(f'v {np.cos(a)} {np.sin(a)} 0\n' for a in np.arange(6) * np.pi / 3)
    (tmp_path / 'fans.obj').write_text(hexagons + 'f 1 2 3 4 5 6\n' * 6)
    with pytest.raises(ShapeFileError,
                       match=r'fans.obj, line 10: more than 12 facets .*16 so far'):
        read_mesh(tmp_path / 'fans.obj')
    write_counts(tmp_path / 'many.tab', v, f)
    with pytest.raises(ShapeFileError, match=r'many.tab, line 1: more than 12 facets .*80 '
                       'announced'):
        read_mesh(tmp_path / 'many.tab')


def test_a_polyhedron_above_the_facet_limit_is_refused_before_its_checks(monkeypatch):
    import tumble_ros.core.model.mass_models as mass_models
    monkeypatch.setattr(mass_models, 'MAX_FACETS', 79)
    v, f = ellipsoid_mesh(AXES, 1)
    with pytest.raises(MassModelError, match='facets: at most 79 facets and vertices '
                       r'\(MAX_FACETS.*got .80 facets and 42 vertices'):
        Polyhedron(v, f, DENSITY)


@pytest.mark.parametrize('scale, message', [
    (1e200, r'line 1: vertices\[0\]: a coordinate beyond 100000 km \(MAX_BODY_SIZE'),
    (1e-9, r'vertices: a body 2e-09 km across is outside \[1e-05, 100000\] km'),
])
def test_a_body_too_large_or_too_small_is_refused_naming_the_line(tmp_path, scale, message):
    """1e200 km was a 70-line OverflowError; a body 2 micrometres across had no bound."""
    v, f = box_mesh((1.0, 1.0, 1.0))
    write_obj(tmp_path / 'box.obj', v * scale, f)
    with pytest.raises(ShapeFileError, match=message):
        load_shape(tmp_path / 'box.obj', DENSITY)


def test_an_ellipsoid_of_1e_300_km_is_refused_not_divided_by_zero():
    with pytest.raises(MassModelError,
                       match=r'semi_axes\[0\]: a body 2e-300 km across .*MIN_BODY'):
        Ellipsoid((1e-300, 1e-300, 1e-300), DENSITY)
    Ellipsoid((1e-5, 1e-5, 1e-5), DENSITY)          # 2e-5 km: accepted


def test_density_moments_of_a_degree_above_the_limit_are_refused_before_any_array():
    """Degree 100,000 asked for a 74.5-GiB array and ended in a 51-line traceback."""
    with pytest.raises(MassModelError, match=r'stokes\[4\]: degree n at most 30 .*got 100000.0'):
        DensityMoments.from_parameters({'mass': 1e10, 'reference_radius': 1.0,
                                        'principal_moments': (1.0, 1.0, 1.0),
                                        'stokes': [2, 0, 0.0, 0.0, 100000, 0, 0.0, 0.0]})


@pytest.mark.parametrize('encoding, said', [
    ('utf-16', 'UTF-16 text'), ('utf-16-le', 'UTF-16 text'), ('utf-32', 'UTF-32 text')])
def test_a_shape_file_in_utf16_or_utf32_is_refused_by_name(tmp_path, encoding, said):
    """It read as '0 vertices and 0 facets' (the NUL bytes made every line unreadable)."""
    v, f = box_mesh((1.0, 1.0, 1.0))
    write_obj(tmp_path / 'box.obj', v, f)
    text = (tmp_path / 'box.obj').read_text()
    (tmp_path / 'wide.obj').write_text(text, encoding=encoding)
    with pytest.raises(ShapeFileError, match=f'wide.obj: cannot read it as text: it holds {said}'):
        read_mesh(tmp_path / 'wide.obj')
    (tmp_path / 'bom.obj').write_text(text, encoding='utf-8-sig')    # a UTF-8 BOM: read
    assert len(read_mesh(tmp_path / 'bom.obj').facets) == 12


def test_a_refused_stokes_coefficient_is_quoted_as_written():
    """The value was quoted as numpy's repr: 'got np.float64(-0.1)'."""
    with pytest.raises(MassModelError, match=r'stokes C\[2, 0\]: must agree .*, got -0.1$'):
        DensityMoments.from_parameters({'mass': 5e10, 'reference_radius': 0.2,
                                        'principal_moments': (1.0e8, 1.5e8, 2.0e8),
                                        'stokes': [2.0, 0.0, -0.1, 0.0]})
