#!/usr/bin/env python3
"""Checks a scene folder's cameras: camera.json, the EXR headers and the pixels agree.

Usage: tests/accuracy/training/check_cameras.py SCENE_DIR...   (e.g. ../shared/data/room)

For each frame of SCENE_DIR/camera.json:
  - worldToCamera and worldToNDC computed by camera_matrices.py from Blender's
    camera_to_world_gl and projection_gl equal the file's own fields and the frame's header
    attributes (printed by iinfo with 6 significant digits, hence the tolerance);
  - the world Position pass, projected through the header's worldToNDC (divide by w), lands on
    its pixel centre, and its camera-space z (header worldToCamera) equals Depth.Z. Position is
    pixel-filtered and Depth is not, so pixels on silhouettes differ: the median and the 90th
    percentile are checked, the maximum is printed.
Prints one line per frame and exits 1 if any check fails. Needs python3 and OIIO's iinfo and
oiiotool (no numpy).
"""

import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import camera_matrices  # noqa: E402

MATRIX_TOLERANCE = 2e-5  # relative to the matrix's largest entry: %g prints 6 digits
PIXEL_TOLERANCE = 0.02   # px, median and 90th percentile of the reprojection offset
DEPTH_TOLERANCE = 1e-3   # relative, median and 90th percentile of |z - Depth.Z| / Depth.Z


def header_matrices(exr):
    text = subprocess.run(["iinfo", "-v", exr], check=True, capture_output=True,
                          text=True).stdout
    out = {}
    for name in ("worldToCamera", "worldToNDC"):
        m = re.search(r"^\s*" + name + r": (.*)$", text, re.M)
        out[name] = [float(v) for v in m.group(1).split(",")] if m else None
    return out


def pixels(exr, names):
    """{channel: list of values} and (width, height) from oiiotool --dumpdata."""
    text = subprocess.run(["oiiotool", "--dumpdata", exr], check=True, capture_output=True,
                          text=True).stdout
    channels = re.search(r"channel list: (.*)", subprocess.run(
        ["iinfo", "-v", exr], check=True, capture_output=True, text=True).stdout).group(1)
    channels = [c.strip() for c in channels.split(",")]
    index = [channels.index(n) for n in names]
    values = {n: [] for n in names}
    coords = []
    for m in re.finditer(r"Pixel \((\d+), (\d+)\): (.*)", text):
        v = m.group(3).split()
        coords.append((int(m.group(1)), int(m.group(2))))
        for n, i in zip(names, index):
            values[n].append(float(v[i]))
    width = max(x for x, _ in coords) + 1
    height = max(y for _, y in coords) + 1
    return coords, values, width, height


def max_relative_difference(a, b):
    scale = max(abs(v) for v in b)
    return max(abs(x - y) for x, y in zip(a, b)) / scale


def percentile(values, p):
    s = sorted(values)
    return s[min(len(s) - 1, int(p * len(s)))]


def check_frame(scene_dir, scene, entry):
    exr = os.path.join(scene_dir, "%s.%04d.exr" % (scene, entry["frame"]))
    ok = True
    w2c = camera_matrices.world_to_camera(entry["camera_to_world_gl"])
    ndc = camera_matrices.world_to_ndc(entry["camera_to_world_gl"], entry["projection_gl"])
    header = header_matrices(exr)
    worst = 0.0
    for name, mine in (("worldToCamera", w2c), ("worldToNDC", ndc)):
        for source, theirs in (("camera.json", entry.get(name)), ("header", header[name])):
            if theirs is None:
                print(f"{exr}: no {name} in {source}")
                ok = False
                continue
            worst = max(worst, max_relative_difference(mine, theirs))
    ok = ok and worst < MATRIX_TOLERANCE
    if header["worldToNDC"] is None or header["worldToCamera"] is None:
        return False
    names = ["ViewLayer.Position.X", "ViewLayer.Position.Y", "ViewLayer.Position.Z",
             "ViewLayer.Depth.Z"]
    coords, v, width, height = pixels(exr, names)
    offsets, depth_errors = [], []
    for i, (x, y) in enumerate(coords):
        depth = v["ViewLayer.Depth.Z"][i]
        if not depth < 1e9:
            continue
        p = (v[names[0]][i], v[names[1]][i], v[names[2]][i])
        hx, hy, _, hw = camera_matrices.transform_point(header["worldToNDC"], p)
        px, py = hx / hw * width, hy / hw * height
        offsets.append(((px - (x + 0.5)) ** 2 + (py - (y + 0.5)) ** 2) ** 0.5)
        z = camera_matrices.transform_point(header["worldToCamera"], p)[2]
        depth_errors.append(abs(z - depth) / depth)
    if not offsets:
        print(f"{exr}: no surface pixels")
        return False
    pixel_ok = percentile(offsets, 0.5) < PIXEL_TOLERANCE and \
        percentile(offsets, 0.9) < PIXEL_TOLERANCE
    depth_ok = percentile(depth_errors, 0.5) < DEPTH_TOLERANCE and \
        percentile(depth_errors, 0.9) < DEPTH_TOLERANCE
    print("%s: matrices %.1e %s; reprojection px median %.4f p90 %.4f max %.2f %s; "
          "z/Depth rel. median %.1e p90 %.1e %s" % (
              exr, worst, "ok" if worst < MATRIX_TOLERANCE else "FAIL",
              percentile(offsets, 0.5), percentile(offsets, 0.9), max(offsets),
              "ok" if pixel_ok else "FAIL", percentile(depth_errors, 0.5),
              percentile(depth_errors, 0.9), "ok" if depth_ok else "FAIL"))
    return ok and pixel_ok and depth_ok


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    ok = True
    for scene_dir in sys.argv[1:]:
        with open(os.path.join(scene_dir, "camera.json")) as f:
            cameras = json.load(f)
        for entry in cameras["frames"]:
            ok = check_frame(scene_dir, cameras["scene"], entry) and ok
    sys.exit(0 if ok else 1)


main()
