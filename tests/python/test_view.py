"""corrlap.view (docs/viewer.md): the page holds the arrays given, decoded here with the standard
library as viewer/README.md describes (zlib, byte planes, id differences); the same page as the
CLI's `corrlap view` for the same mesh; errors name the argument. The page in a browser:
tests/viewer/browser_test.mjs.
"""
import base64
import json
import os
import re
import subprocess
import zlib

import numpy as np
import pytest

import corrlap

needs_viewer = pytest.mark.skipif(not corrlap._core.has_viewer(), reason="this build has no viewer (no node/npm)")


def decode(html):
    scene = json.loads(re.search(r'id="corrlap-scene">(.*?)</script>', html, re.S).group(1))
    data = base64.b64decode(re.search(r'id="corrlap-data">(.*?)</script>', html, re.S).group(1))
    if scene["data"]["encoding"] == "deflate+base64":
        data = zlib.decompress(data)
    assert len(data) == scene["data"]["bytes"]

    def array(a):
        n, at = a["count"], a["offset"]
        if a["type"] == "uint8":
            return np.frombuffer(data, np.uint8, n, at)
        planes = np.frombuffer(data, np.uint8, 4 * n, at).reshape(4, n)
        words = planes.T.copy().view("<u4").ravel()  # byte k of every element is plane k
        if a["filter"] == "delta+shuffle":
            words = np.cumsum(words, dtype=np.uint32)  # modulo 2^32, as written
        return words.view(np.float32) if a["type"] == "float32" else words

    return scene, array


@needs_viewer
def test_view_holds_the_arrays_and_colours_like_the_pictures(tmp_path):
    V, F = corrlap.digitize("sphere1", h=0.2, bbox=(-1.5, 1.5))
    z = V[:, 2].copy()
    ids = np.arange(len(F), dtype=float)
    tri_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    page = corrlap.view(V, F, scalars={"z": z, "ids": ids}, path=tmp_path / "v.html", name="sphere",
                        others=[dict(V=tri_V, F=[[0, 1, 2]], name="triangle", visible=False)])
    assert page.path == str(tmp_path / "v.html")
    assert open(page.path).read() == page.html
    assert "<iframe srcdoc=" in page._repr_html_()
    scene, array = decode(page.html)
    sphere, triangle = scene["meshes"]
    assert sphere["name"] == "sphere" and sphere["visible"] and not triangle["visible"]
    np.testing.assert_array_equal(array(sphere["positions"]).reshape(-1, 3), V.astype(np.float32))
    assert sphere["face_size"] == 4 and triangle["face_size"] == 3
    np.testing.assert_array_equal(array(sphere["corners"]).reshape(-1, 4), F)
    np.testing.assert_array_equal(array(sphere["vertex_fields"]["z"]), z.astype(np.float32))
    np.testing.assert_array_equal(array(sphere["face_fields"]["ids"]), ids.astype(np.float32))  # by its length
    np.testing.assert_array_equal(array(triangle["corners"]), [0, 1, 2])
    # z takes both signs: the diverging map, symmetric about 0 at the 98th percentile of |z|.
    fields = {f["name"]: f for f in scene["fields"]}
    assert fields["z"]["colormap"] == "diverging"
    assert fields["z"]["max"] == -fields["z"]["min"] == np.sort(np.abs(z))[int(0.98 * (len(z) - 1))]
    assert fields["ids"]["colormap"] == "sequential"
    assert scene["initial_field"] == "z"  # auto without H: the first field
    assert corrlap.view(V, F, scalars={"z": z}, field="none").path is None


@needs_viewer
def test_view_gives_the_page_of_the_cli():
    cli = os.environ.get("CORRLAP_CLI")
    if not cli:
        pytest.skip("CORRLAP_CLI is not set")
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        V, F = corrlap.digitize("sphere1", h=0.25, bbox=(-1.5, 1.5))
        H = np.linalg.norm(V, axis=1)
        corrlap.write_mesh(f"{d}/s.ply", V, F, vertex_scalars={"H": H})
        subprocess.run([cli, "view", f"{d}/s.ply", "--title", "t", "--out", f"{d}/cli.html"], check=True,
                       capture_output=True)
        page = corrlap.view(V, F, scalars={"H": H}, name="s", title="t")
        assert open(f"{d}/cli.html").read() == page.html


def test_view_names_bad_arguments():
    V, F = corrlap.digitize("sphere1", h=0.5, bbox=(-1.5, 1.5))
    if not corrlap._core.has_viewer():
        with pytest.raises(RuntimeError, match="no viewer"):
            corrlap.view(V, F)
        return
    with pytest.raises(ValueError, match="F: face 0 has vertex id"):
        corrlap.view(V, F + len(V))
    with pytest.raises(ValueError, match="3 <= d <= 255"):
        corrlap.view(V, F[:, :2])
    with pytest.raises(ValueError, match=r"scalars\['s'\]: expected"):
        corrlap.view(V, F, scalars={"s": np.zeros(3)})
    with pytest.raises(ValueError, match="no surface has a field 'K'"):
        corrlap.view(V, F, field="K")
    with pytest.raises(ValueError, match=r"others\[0\]: expected a dict"):
        corrlap.view(V, F, others=[(V, F)])
    with pytest.raises(ValueError, match="not finite"):
        corrlap.view(V * np.nan, F)
