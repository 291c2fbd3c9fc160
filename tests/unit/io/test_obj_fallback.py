"""An OBJ whose texture coordinates do not pair with its vertices (as example-robot-data's
Alex meshes): meshio refuses it, casmech reads its vertices and faces (io.animate.obj_geometry)."""

import numpy as np
import pytest

from casmech.io.animate import mesh_file, meshio_module

TEXT = """# a unit square as one quad and a triangle over it, 6 texture coordinates
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vt 0.5 0.5
vt 0.2 0.2
f 1/1 2/5 3/6 4/2
f -4/1 -3/2 -1/3
"""


def test_an_obj_meshio_refuses_is_read_by_its_vertices_and_faces(tmp_path):
    path = tmp_path / "square.obj"
    path.write_text(TEXT)
    with pytest.raises(ValueError):  # the case the fallback is for
        meshio_module().read(path)
    points, triangles = mesh_file(path, 2.0)
    np.testing.assert_allclose(points, 2.0 * np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0],
                                                       [0, 1, 0]]), rtol=0, atol=0)  # exact
    assert triangles.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 3]]


def test_a_face_past_the_vertices_is_an_error(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text(TEXT.replace("f -4/1 -3/2 -1/3", "f 1/1 2/2 9/3"))
    with pytest.raises(ValueError, match="a face names a vertex"):
        mesh_file(path, 1.0)


def test_a_collada_scene_whose_material_reference_is_broken_keeps_its_node_transform():
    """example-robot-data's ANYmal foot: pycollada binds no geometry of its scene (a texture
    surface is missing), so the node's <instance_geometry> is read from its XML, with the
    node's 0.001 scale of the file's millimetres applied (the foot is 0.36 m long)."""
    from tests.integration.importers.test_urdf_complete import robots_folder

    path = (robots_folder() / "robots/anymal_b_simple_description/meshes/foot/"
            "anymal_foot.dae")
    points, triangles = mesh_file(path, 1.0)
    extent = points.max(axis=0) - points.min(axis=0)
    np.testing.assert_allclose(extent, [0.0619, 0.0619, 0.3613], rtol=1e-3,
                               atol=0)  # the foot's size in metres, read off its vertices
    assert triangles.shape == (4604, 3) and triangles.max() < len(points)
