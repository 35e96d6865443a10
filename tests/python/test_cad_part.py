"""scripts/cad_part.py: the stand-in for the paper's fandisk (Fig. 14). The part must be a closed,
outward polyhedron with the profile's volume, its signed distance must be the exact one, and the
measures of a mesh against it must see what they claim to see."""
import importlib.util
import json
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "cad_part.py")
spec = importlib.util.spec_from_file_location("cad_part", SCRIPT)
cad = importlib.util.module_from_spec(spec)
spec.loader.exec_module(cad)


def shoelace(p):
    return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def test_the_part_is_closed_and_faces_outwards():
    verts, faces = cad.mesh()
    edges = {}
    for f in faces:
        for k in range(3):
            e = (int(f[k]), int(f[(k + 1) % 3]))
            edges[e] = edges.get(e, 0) + 1
    # Every directed edge once, and its reverse once: closed, oriented, manifold.
    assert all(n == 1 for n in edges.values())
    assert all((b, a) in edges for a, b in edges)
    # The profile's area: the 2 x 1.1 rectangle less the chamfer (0.3 x 0.3 / 2), the notch (0.25 x
    # 0.25) and the rounded corner's outside (0.3^2 (1 - pi/4)), the arc as 24 chords.
    arc = 0.5 * 0.3 ** 2 * cad.ARC_SEGMENTS * math.sin(0.5 * math.pi / cad.ARC_SEGMENTS)
    area = 2.0 * 1.1 - 0.045 - 0.0625 - (0.09 - arc)
    assert abs(shoelace(cad.profile()) - area) < 1e-12
    volume = cad.surface_truth.signed_volume(verts, faces)
    assert abs(volume - area * 2 * cad.HALF_THICKNESS) < 1e-12


def test_signed_distance_at_points_checked_by_hand():
    local = np.array([
        [0.0, -0.2, 0.0],   # inside: 0.4 from the bottom face and from both caps
        [0.0, -0.2, 1.0],   # above the top cap by 0.6
        [1.3, -0.9, 0.7],   # off the corner (1, -0.6, 0.4): sqrt(0.3^2 + 0.3^2 + 0.3^2)
        [-0.3, 0.4, 0.0],   # in the notch: 0.1 from its right wall
        [0.95, 0.45, 0.0],  # beyond the chamfer x + y = 1.2, by 0.2 / sqrt(2)
    ])
    expected = [-0.4, 0.6, math.sqrt(0.27), 0.1, 0.2 / math.sqrt(2)]
    world = local @ cad.rotation().T
    assert np.allclose(cad.signed_distance(world), expected, atol=1e-12)
    # The rotation is a rotation, and off every grid axis.
    r = cad.rotation()
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-14)
    assert np.abs(r).max() < 0.99


def test_measures_of_the_part_itself_and_of_a_scaled_copy():
    verts, faces = cad.mesh()
    h = 0.02
    m = cad.measure(verts, faces, h)
    assert m["distance_max"] < 1e-12
    assert abs(m["area_ratio"] - 1.0) < 1e-12 and abs(m["volume_ratio"] - 1.0) < 1e-12
    assert all(a < 1e-3 or math.isnan(a) for a in m["angle_deg"].values())
    # Scaled by 1.01 about the origin (inside the part): the volume by 1.01^3, the area by 1.01^2.
    scaled = cad.measure(1.01 * verts, faces, h)
    assert abs(scaled["volume_ratio"] - 1.01 ** 3) < 1e-9
    assert abs(scaled["area_ratio"] - 1.01 ** 2) < 1e-9
    # No vertex moves farther than 1 % of the largest radius, and the corners, moved outwards along
    # their normal cones, move about that far from the part.
    assert abs(scaled["distance_max"] - 0.01 * np.linalg.norm(verts, axis=1).max()) < 0.002


def test_distance_to_the_sharp_edges():
    samples = cad.sharp_edge_samples(0.01)
    assert np.abs(cad.signed_distance(samples)).max() < 1e-12
    h = 0.01
    local = np.array([
        [0.0, -0.2, 0.4],   # on the top cap: 0.4 from its edge at y = -0.6, 0.7 from the one at y = 0.5
        [0.2, -0.6, 0.1],   # on the side face y = -0.6: 0.3 from the top cap's edge
        [-0.3, 0.25, 0.0],  # on the notch's floor: 0.1 from its right (concave) corner edge
        [-0.7, 0.5, 0.0],   # where the arc meets the top face: no sharp edge there; the notch 0.25 away
    ])
    d = cad.edge_distance(local @ cad.rotation().T, h)
    assert np.allclose(d, [0.4, 0.3, 0.1, 0.25], atol=h / 8)


def test_the_command_line(tmp_path):
    obj = tmp_path / "part.obj"
    subprocess.run([sys.executable, SCRIPT, "write", str(obj)], check=True)
    out = subprocess.run([sys.executable, SCRIPT, "measure", str(obj), "0.05"], check=True,
                         capture_output=True, text=True).stdout
    m = json.loads(out)
    assert m["distance_max"] < 1e-12 and set(m["angle_deg"]) == {"edges", "near", "flats"}
    bad = subprocess.run([sys.executable, SCRIPT, "measure", str(obj), "-1"], capture_output=True, text=True)
    assert bad.returncode == 2 and "positive grid step" in bad.stderr
    missing = subprocess.run([sys.executable, SCRIPT, "measure", str(tmp_path / "none.ply"), "0.05"],
                             capture_output=True, text=True)
    assert missing.returncode == 2 and "cannot read" in missing.stderr and "Traceback" not in missing.stderr
