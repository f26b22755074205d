"""Exact mass properties (thesis ch. 6) against closed forms, an independent tetrahedral
decomposition and the `impulse massprops` program."""

import numpy as np
import pytest

import impulse
from conftest import write_obj

BOX_FACES = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]


def box(a, b, c, centre=(0.0, 0.0, 0.0)):
    """The vertices of an a × b × c box (faces BOX_FACES, counter-clockwise from outside)."""
    x, y, z = a / 2, b / 2, c / 2
    v = np.array(
        [[-x, -y, -z], [x, -y, -z], [x, y, -z], [-x, y, -z],
         [-x, -y, z], [x, -y, z], [x, y, z], [-x, y, z]]
    )
    return v + np.asarray(centre)


def test_box_matches_the_closed_form():
    a, b, c, rho = 0.3, 0.5, 0.7, 1200.0
    p = impulse.mass_properties(box(a, b, c, (1.0, -2.0, 3.0)), BOX_FACES, density=rho)
    m = rho * a * b * c
    assert p.volume == pytest.approx(a * b * c, rel=1e-14)
    assert p.mass == pytest.approx(m, rel=1e-14)
    np.testing.assert_allclose(p.com, [1.0, -2.0, 3.0], rtol=0, atol=1e-14)
    expected = np.diag([b * b + c * c, a * a + c * c, a * a + b * b]) * m / 12
    np.testing.assert_allclose(p.inertia, expected, rtol=1e-13, atol=1e-15 * m)
    np.testing.assert_allclose(p.principal_moments, np.sort(np.diag(expected)), rtol=1e-13)
    assert p.inertia.shape == (3, 3) and p.com.shape == (3,)


def test_box_equals_the_cli(cli, tmp_path):
    v = box(0.3, 0.5, 0.7, (0.1, 0.2, 0.3))
    write_obj(tmp_path / "box.obj", v, BOX_FACES)
    ref = cli.json("massprops", tmp_path / "box.obj", "--mass", "2.5")
    p = impulse.mass_properties(v, np.array(BOX_FACES), mass=2.5)
    assert p.mass == pytest.approx(ref["mass"], rel=1e-15)
    assert p.volume == pytest.approx(ref["volume"], rel=1e-15)
    np.testing.assert_allclose(p.com, ref["com"], rtol=1e-15, atol=1e-17)
    np.testing.assert_allclose(p.inertia, ref["inertia"], rtol=1e-14, atol=1e-17)


def tetra_reference(vertices, faces, density):
    """Mass, centre of mass and inertia about it, by tetrahedra from the origin: a fan of each
    face, the canonical tetrahedron's covariance (independent of the thesis's projections)."""
    canonical = np.array([[2.0, 1, 1], [1, 2, 1], [1, 1, 2]]) / 120.0
    vol, first, cov = 0.0, np.zeros(3), np.zeros((3, 3))
    for face in faces:
        for k in range(1, len(face) - 1):
            a = np.column_stack([vertices[face[0]], vertices[face[k]], vertices[face[k + 1]]])
            d = np.linalg.det(a)
            vol += d / 6
            first += d / 24 * a.sum(axis=1)
            cov += d * a @ canonical @ a.T
    m = density * vol
    com = first / vol
    inertia_o = density * (np.trace(cov) * np.eye(3) - cov)
    inertia = inertia_o - m * (com @ com * np.eye(3) - np.outer(com, com))
    return m, com, inertia


def test_random_hull_matches_tetrahedra_and_the_cli(cli, tmp_path):
    rng = np.random.default_rng(7)
    pts = rng.normal(size=(60, 3)) * [0.2, 0.1, 0.05] + [0.3, -0.1, 0.2]
    v, f = impulse.convex_hull(pts)
    assert v.shape[1] == 3 and all(len(face) >= 3 for face in f)
    p = impulse.mass_properties(v, f, density=900.0)
    m, com, inertia = tetra_reference(v, f, 900.0)
    assert p.mass == pytest.approx(m, rel=1e-12)
    np.testing.assert_allclose(p.com, com, rtol=0, atol=1e-13)
    np.testing.assert_allclose(p.inertia, inertia, rtol=0, atol=1e-11 * np.abs(inertia).max())
    write_obj(tmp_path / "hull.obj", v, f)
    ref = cli.json("massprops", tmp_path / "hull.obj", "--density", "900")
    assert p.mass == pytest.approx(ref["mass"], rel=1e-15)
    np.testing.assert_allclose(p.com, ref["com"], rtol=1e-15, atol=1e-17)
    np.testing.assert_allclose(p.inertia, ref["inertia"], rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(p.principal_axes, ref["principal_axes"], atol=1e-12)


def test_obj_file_equals_the_cli(cli, root):
    path = root / "fixtures/meshes/frame.obj"  # non-convex, genus 1
    p = impulse.mass_properties_obj(path, density=2.0)
    ref = cli.json("massprops", path, "--density", "2")
    assert p.volume == ref["volume"] and p.mass == ref["mass"]
    np.testing.assert_array_equal(p.com, ref["com"])
    np.testing.assert_array_equal(p.inertia, ref["inertia"])
