"""scikit-image's conventions (issue 37): level, spacing and origin, vertex normals, a Mesh result
that unpacks as (V, F), stats on the mesh's topology, sample() placed as the CLI places it."""
import numpy as np
import pytest

import sdfcontour

skimage_measure = pytest.importorskip("skimage.measure")

SHAPE = (20, 26, 17)
SPACING = np.array([0.5, 1.0, 2.0])
ORIGIN = np.array([1.0, -2.0, 3.0])
CENTRE = ORIGIN + SPACING * (np.array(SHAPE) - 1) / 2
STRETCH = np.array([1.0, 1.3, 1.1])


def ellipsoid_field(P):
    return np.linalg.norm((P - CENTRE) / STRETCH, axis=-1) - 3.5


def anisotropic_grid():
    axes = [ORIGIN[a] + np.arange(SHAPE[a]) * SPACING[a] for a in range(3)]
    return ellipsoid_field(np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1))


def sorted_rows(A):
    return A[np.lexsort(A.T[::-1])]


def test_level_spacing_origin_give_scikit_images_vertices_plus_the_origin():
    vol = anisotropic_grid()
    verts, faces, _, _ = skimage_measure.marching_cubes(vol, level=0.3, spacing=tuple(SPACING))
    V, F = sdfcontour.contour(vol, method="mc", level=0.3, spacing=SPACING, origin=ORIGIN)
    assert V.shape == verts.shape and F.shape == faces.shape
    # scikit-image computes in float32: equal to its rounding.
    assert np.abs(sorted_rows(V) - sorted_rows(verts + ORIGIN)).max() < 1e-5
    # The level set f = 0.3 of this field lies where |(P - c) / stretch| = 3.8 (chords of cells
    # up to 2 long cut inside by up to 0.1).
    assert np.abs(np.linalg.norm((V - CENTRE) / STRETCH, axis=1) - 3.8).max() < 0.15


def test_normals_follow_the_fields_gradient_on_an_anisotropic_grid():
    mesh = sdfcontour.contour(anisotropic_grid(), method="mc", spacing=SPACING, origin=ORIGIN,
                              return_normals=True)
    V, F, N = mesh
    exact = (V - CENTRE) / STRETCH ** 2
    exact /= np.linalg.norm(exact, axis=1, keepdims=True)
    dots = np.sum(exact * N, axis=1)
    assert dots.min() > 0.995 and dots.mean() > 0.999 and np.allclose(np.linalg.norm(N, axis=1), 1)
    assert mesh.normals is N


def test_callable_normals_and_level():
    def sphere(P):
        return np.linalg.norm(P, axis=1) - 0.5
    V, F, N, stats = sdfcontour.contour(sphere, resolution=33, method="mc", level=0.1,
                                        return_normals=True, return_stats=True)
    assert np.abs(np.linalg.norm(V, axis=1) - 0.6).max() < 0.01
    assert np.sum(N * V / np.linalg.norm(V, axis=1, keepdims=True), axis=1).min() > 0.9999
    assert stats["normal_evaluations"] == 6 * len(V)
    # The same as contouring the field less the level.
    V2, F2 = sdfcontour.contour(lambda P: sphere(P) - 0.1, resolution=33, method="mc")
    assert np.array_equal(V, V2) and np.array_equal(F, F2)


def test_mesh_result_unpacks_and_names_its_parts():
    axis = np.linspace(-1, 1, 40)
    P = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1)
    two_spheres = np.minimum(np.linalg.norm(P - [0.45, 0, 0], axis=-1) - 0.3,
                             np.linalg.norm(P + [0.45, 0, 0], axis=-1) - 0.3)
    mesh = sdfcontour.contour(two_spheres, method="mc")
    V, F = mesh
    assert isinstance(mesh, sdfcontour.Mesh) and isinstance(mesh, tuple) and len(mesh) == 2
    assert mesh.V is V and mesh.F is F and mesh.normals is None
    assert mesh.stats["closed"] and mesh.stats["manifold"] and mesh.stats["oriented"]
    assert mesh.stats["components"] == 2
    assert "2 components" not in repr(mesh) and "triangles" in repr(mesh)
    V, F, stats = sdfcontour.contour(two_spheres, return_stats=True)  # GCP, as before
    assert stats["closed"] and stats["components"] == 2


@pytest.mark.parametrize("kwargs, words", [
    (dict(bounds=(-1, 1), spacing=0.1), "not both"),
    (dict(spacing=-1.0), "positive"),
    (dict(spacing=(1, 2)), "3 numbers"),
    (dict(level=np.nan), "level"),
    (dict(level="0"), "level"),
])
def test_bad_placement_is_refused(kwargs, words):
    with pytest.raises((ValueError, TypeError), match=words):
        sdfcontour.contour(anisotropic_grid(), method="mc", **kwargs)


def test_spacing_is_for_grids_only():
    samples = np.random.default_rng(0).uniform(-1, 1, (500, 4))
    with pytest.raises(ValueError, match="scattered samples carry their own positions"):
        sdfcontour.contour(samples, spacing=0.1)
