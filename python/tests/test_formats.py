"""Python reads what the command line reads (issue 32 item 4): `load`, `convert`,
`read_mesh` and `render` recognize files by content through the session layer's `identify`
and read STEP (with trimmed faces), IGES, triangular NURBS and lattices with vclay-io's
readers; files that are sessions say what opens them."""

import numpy as np
import pytest

import vclay

CAD = "crates/vclay-io/tests/data/cad"


def test_step_and_iges_load_and_convert(root, tmp_path):
    torus = vclay.load(root / CAD / "brep_torus.step")
    assert torus and all(isinstance(e, vclay.Surface) for e in torus)
    vclay.convert(root / CAD / "brep_torus.step", tmp_path / "torus.json")
    again = vclay.load(tmp_path / "torus.json")
    assert again == torus
    vclay.convert(root / CAD / "brep_box.step", tmp_path / "box.obj", samples=8)
    v, t, _ = vclay.read_mesh(tmp_path / "box.obj")
    assert len(t) > 0
    cyl = vclay.load(root / CAD / "iges_cylinder.igs")
    assert any(isinstance(e, vclay.Surface) for e in cyl)
    curve = vclay.load(root / CAD / "curve.step")
    assert isinstance(curve[0], vclay.Curve)
    vclay.render(root / CAD / "brep_sphere.step", tmp_path / "s.png", size=(64, 48))
    assert (tmp_path / "s.png").stat().st_size > 0


def test_triangular_and_lattices(root, tmp_path):
    tri = root / "examples/triangular/saddle_patch.json"
    vclay.convert(tri, tmp_path / "saddle.stl")
    v, t, _ = vclay.read_mesh(tri)
    assert len(t) > 0 and np.isfinite(v).all()
    with pytest.raises(vclay.FileError, match="read_mesh"):
        vclay.load(tri)
    lat = tmp_path / "box.ovm"
    vclay.Lattice.primitive("box").write(lat)
    patches = vclay.load(lat)
    assert patches and all(isinstance(p, vclay.Surface) for p in patches)
    vclay.Lattice.primitive("box").subdivide(1).write(tmp_path / "box.vtu")
    v, t, _ = vclay.read_mesh(tmp_path / "box.vtu")
    assert len(t) > 0


def test_files_that_are_not_models_say_what_opens_them(root, tmp_path):
    with pytest.raises(vclay.FileError, match="vclay.open"):
        vclay.load(root / "examples/scenarios/fig07_rope_cube.toml")
    with pytest.raises(vclay.FileError, match="PdeSurface.read"):
        vclay.load(root / "examples/pde/fig5b.json")
    cloud = tmp_path / "scan.xyz"
    cloud.write_text("0 0 0\n1 0 0\n0 1 1\n")
    with pytest.raises(vclay.FileError, match="fit_surface"):
        vclay.convert(cloud, tmp_path / "x.obj")
    # Content decides; a STEP file named .json is refused with the extension to use.
    wrong = tmp_path / "torus.json"
    wrong.write_bytes((root / CAD / "brep_torus.step").read_bytes())
    with pytest.raises(vclay.FileError, match="rename it"):
        vclay.load(wrong)


def glb_to_gltf(glb_path, gltf_path, embed):
    """The JSON and BIN chunks of a .glb as a .gltf (buffer embedded or beside it)."""
    import base64
    import json
    import struct

    b = glb_path.read_bytes()
    n = struct.unpack_from("<I", b, 12)[0]
    doc = json.loads(b[20:20 + n])
    m = struct.unpack_from("<I", b, 20 + n)[0]
    binary = b[28 + n:28 + n + m]
    if embed:
        doc["buffers"][0]["uri"] = ("data:application/octet-stream;base64,"
                                    + base64.b64encode(binary).decode())
    else:
        (gltf_path.parent / "mesh.bin").write_bytes(binary)
        doc["buffers"][0]["uri"] = "mesh.bin"
    gltf_path.write_text(json.dumps(doc))


def test_gltf_reads_like_glb(root, tmp_path):
    surf = vclay.load(root / CAD / "brep_torus.step")
    vclay.save(tmp_path / "t.glb", surf, samples=6)
    v0, t0, _ = vclay.read_mesh(tmp_path / "t.glb")
    for embed in (True, False):
        p = tmp_path / f"t{int(embed)}.gltf"
        glb_to_gltf(tmp_path / "t.glb", p, embed)
        v, t, _ = vclay.read_mesh(p)
        np.testing.assert_array_equal(v, v0)
        np.testing.assert_array_equal(t, t0)
    vclay.convert(tmp_path / "t1.gltf", tmp_path / "t.obj")
    assert len(vclay.read_mesh(tmp_path / "t.obj")[1]) == len(t0)
