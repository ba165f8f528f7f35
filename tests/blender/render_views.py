"""Renders the views of a shot: what surrounds the shot camera, per frame, as G-buffer EXRs.

Usage (Blender 3.4, headless; needs OIIO's oiiotool on PATH):
  blender -b FILE.blend --python-exit-code 1 --python tests/blender/render_views.py -- \
      --out DIR [--name NAME] [--frames FIRST-LAST | --frames FRAME] [--camera OBJECT]
      [--face-size N] [--latlong-width N] [--samples N] [--faces-only | --latlong-only]
      [--with-indirect]

For each frame (default: the scene's frame range) it renders, from the shot camera's world
position at that frame:
  DIR/NAME.<face>.####.exr   six pinhole cube faces, N x N pixels (--face-size, default 128),
                             face one of px, nx, py, ny, pz, nz;
  DIR/NAME.latlong.####.exr  a lat-long (equirectangular) panorama covering 360 x 180 degrees,
                             W x W/2 pixels (--latlong-width, default 512, even);
NAME defaults to the .blend's file name without its extension, the shot camera to the one the
scene renders each frame with (scene.camera, camera markers included); --camera names another
camera object. --faces-only and --latlong-only render one kind of view. --with-indirect also
writes the path-traced diffuse indirect light (DiffInd, at the .blend's own bounces: a render
about twice as long), the truth to measure the light ssgi computes for the views against.

Faces are named in the shot camera's own frame (Blender camera space: x right, y up, looking
along -z), each face camera looking along (image top towards):
  pz  -z, forward     (+y, the camera's up)        nz  +z, backward  (+y)
  px  +x, right       (+y)                         nx  -x, left      (+y)
  py  +y, up          (+z, the camera's backward)  ny  -y, down      (-z, the camera's forward)
A face camera is a perspective camera at the shot camera's position with horizontal and vertical
fields of view of exactly 90 degrees (18 mm lens on a 36 mm sensor, square pixels, no shift) and
the shot camera's clip range. The lat-long camera is Cycles' panoramic EQUIRECTANGULAR camera
(latitude -90..90, longitude -180..180 degrees) with the shot camera's position and rotation:
the image centre looks along the shot camera's forward direction, the top row straight up along
its +y. The shot camera's scale is ignored (Cycles ignores it too).

Rendering: Cycles CPU, --samples per pixel (default 16), no adaptive sampling, no denoising, no
motion blur, a 0.01-pixel filter (every sample at the pixel centre, so the data passes are the
exact values there, as tests/blender/render_gbuffer.py renders), no compositing, max bounces 0
(the passes below are the first surface and its direct light: they come out identical to a
render at Blender's default bounces, in half the time); multilayer 32-bit float ZIP EXR with,
on every view layer the .blend renders, the passes ssgi reads: Depth, Normal, Position, DiffCol,
DiffDir, Emit (and Combined, which Blender always writes; every other built-in pass is turned
off, shader AOVs and light groups the .blend defines are kept).
Depth is Cycles': planar camera z on a face, the distance along the pixel's ray on the lat-long.
The .blend is not saved.

Cameras in the headers: stock Blender writes none. Each view renders to a hidden file
DIR/.NAME.<view>.####.exr; once a frame's views are rendered, oiiotool writes them to their
names with the OpenEXR standard attributes added, as tests/accuracy/training/render.sh adds them
(Imath row-vector matrices, p' = p * M, translation in the last row), and the hidden files go:
  faces:    worldToCamera (x right, y up, +z forward) and worldToNDC ((0,0) top-left, (1,1)
            bottom-right after the divide by w), from the face camera's matrix_world and
            Blender's projection by ../accuracy/training/camera_matrices.py, as for a shot frame;
  lat-long: worldToCamera only: the inverse of the panorama camera's matrix_world in Blender's
            own camera space (x right, y up, looking along -z; not flipped), as ssgi reads a
            lat-long view's camera. The pixel centre (u + 0.5, v + 0.5) of the W x H map, v = 0
            the top row, looks along longitude phi = ((u + 0.5) / W - 0.5) * 2 pi and latitude
            theta = (0.5 - (v + 0.5) / H) * pi, i.e. along (cos theta sin phi, sin theta,
            -cos theta cos phi) in that camera space: the centre forward, a quarter across
            left (-x), three quarters across right (+x), the left and right edges backward.
DIR/NAME.views.json holds the same matrices per frame and view, with Blender's camera-to-world
and projection matrices they come from.
"""

import json
import math
import os
import shutil
import subprocess
import sys
import time

import bpy
from mathutils import Matrix

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "accuracy",
                                "training"))
import camera_matrices  # noqa: E402

# Each face's rotation in the shot camera's frame: the columns are the face camera's x (right),
# y (image up) and z (backward) axes in shot camera coordinates.
FACES = {
    "px": ((0, 0, 1), (0, 1, 0), (-1, 0, 0)),
    "nx": ((0, 0, -1), (0, 1, 0), (1, 0, 0)),
    "py": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
    "ny": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "pz": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "nz": ((-1, 0, 0), (0, 1, 0), (0, 0, -1)),
}
PASSES = ("z", "normal", "position", "diffuse_color", "diffuse_direct", "emit")
FACE_LENS_MM, FACE_SENSOR_MM = 18.0, 36.0  # 2 * atan(18 / 36) = 90 degrees


def fail(message):
    raise SystemExit("render_views.py: " + message)


def parse_args(argv):
    opts = {"out": None, "name": None, "frames": None, "camera": None, "face_size": 128,
            "latlong_width": 512, "samples": 16, "faces": True, "latlong": True,
            "indirect": False}
    numbers = {"--face-size": "face_size", "--latlong-width": "latlong_width",
               "--samples": "samples"}
    i = 0
    while i < len(argv):
        arg = argv[i]
        if arg in ("--faces-only", "--latlong-only"):
            opts["latlong" if arg == "--faces-only" else "faces"] = False
            i += 1
            continue
        if arg == "--with-indirect":
            opts["indirect"] = True
            i += 1
            continue
        if i + 1 >= len(argv):
            fail(f"unknown argument or missing value: {arg!r} (see the usage at the top)")
        value = argv[i + 1]
        if arg in ("--out", "--name", "--camera"):
            opts[arg[2:]] = value
        elif arg == "--frames":
            try:
                first, _, last = value.partition("-")
                opts["frames"] = (int(first), int(last or first))
            except ValueError:
                fail(f"--frames takes FIRST-LAST or FRAME, not {value!r}")
        elif arg in numbers:
            try:
                opts[numbers[arg]] = int(value)
            except ValueError:
                fail(f"{arg} takes a whole number, not {value!r}")
        else:
            fail(f"unknown argument {arg!r} (see the usage at the top)")
        i += 2
    if not opts["out"]:
        fail("give the output directory: --out DIR")
    if not (opts["faces"] or opts["latlong"]):
        fail("--faces-only and --latlong-only exclude each other")
    if opts["face_size"] < 1 or opts["samples"] < 1:
        fail("--face-size and --samples must be positive")
    if opts["latlong_width"] < 2 or opts["latlong_width"] % 2:
        fail("--latlong-width must be even and positive (the height is half of it)")
    return opts


def render_settings(scene, samples, indirect):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.time_limit = 0.0
    scene.cycles.use_denoising = False
    scene.cycles.film_filter_width = 0.01
    if not indirect:
        scene.cycles.max_bounces = 0
    scene.render.use_motion_blur = False
    # Cycles keeps the synced scene from one view to the next (the same pixels; heavy scenes
    # skip rebuilding their BVH per view).
    scene.render.use_persistent_data = True
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.render.use_border = False
    scene.render.use_multiview = False
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    scene.render.use_file_extension = False
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    settings.views_format = "INDIVIDUAL"
    for layer in scene.view_layers:
        for owner in (layer, layer.cycles):
            for prop in owner.bl_rna.properties:
                if prop.identifier.startswith("use_pass_") and not prop.is_readonly:
                    setattr(owner, prop.identifier, False)
        for p in PASSES + (("diffuse_indirect",) if indirect else ()):
            setattr(layer, "use_pass_" + p, True)
        layer.cycles.use_denoising = False
        layer.cycles.denoising_store_passes = False


def shot_cameras(scene, name, frames):
    """{frame: camera object} the shot is rendered with; camera markers are unbound after."""
    out = {}
    for f in frames:
        scene.frame_set(f)
        cam = bpy.data.objects.get(name) if name else scene.camera
        if cam is None or cam.type != "CAMERA":
            fail(f"no camera object {name!r}" if name else f"the scene has no camera at frame {f}")
        out[f] = cam
    # The views render with their own cameras: markers must not switch back to the shot's.
    for marker in scene.timeline_markers:
        marker.camera = None
    return out


def rigid(matrix):
    """matrix_world without its scale: rotation and translation."""
    location, rotation, _ = matrix.decompose()
    return Matrix.Translation(location) @ rotation.to_matrix().to_4x4()


def add_view_cameras(scene):
    face_data = bpy.data.cameras.new("views_face")
    face_data.type = "PERSP"
    face_data.sensor_fit = "HORIZONTAL"
    face_data.sensor_width = face_data.sensor_height = FACE_SENSOR_MM
    face_data.lens = FACE_LENS_MM
    face_data.shift_x = face_data.shift_y = 0.0
    face = bpy.data.objects.new("views_face", face_data)
    pano_data = bpy.data.cameras.new("views_latlong")
    pano_data.type = "PANO"
    pano_data.cycles.panorama_type = "EQUIRECTANGULAR"
    pano_data.cycles.latitude_min, pano_data.cycles.latitude_max = -math.pi / 2, math.pi / 2
    pano_data.cycles.longitude_min, pano_data.cycles.longitude_max = -math.pi, math.pi
    pano = bpy.data.objects.new("views_latlong", pano_data)
    for obj in (face, pano):
        scene.collection.objects.link(obj)
    return face, pano


def add_headers(views):
    """views: (rendered, path, worldToCamera, worldToNDC or None). Writes each rendered file
    to path with the OpenEXR camera attributes in its header, as render.sh adds them (one
    oiiotool run for all: its start-up costs more than a small file), and removes it."""
    args = ["oiiotool", "--nosoftwareattrib"]
    for rendered, path, world_to_camera, world_to_ndc in views:
        args += [rendered, "--attrib:type=matrix", "worldToCamera",
                 ",".join(repr(v) for v in world_to_camera)]
        if world_to_ndc is not None:
            args += ["--attrib:type=matrix", "worldToNDC",
                     ",".join(repr(v) for v in world_to_ndc)]
        args += ["-o", path]
    subprocess.run(args, check=True)
    for rendered, *_ in views:
        os.remove(rendered)


def render_view(scene, cam, size, path):
    """Renders cam's view to a hidden file beside path (path itself is written with the
    camera in its header) and returns that file's name."""
    rendered = os.path.join(os.path.dirname(path), "." + os.path.basename(path))
    if os.path.exists(rendered):
        os.remove(rendered)  # left by an interrupted run
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.filepath = rendered
    bpy.ops.render.render(write_still=True)
    if not os.path.isfile(rendered):
        fail(f"Blender wrote no {rendered}")
    return rendered


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    opts = parse_args(argv)
    if shutil.which("oiiotool") is None:
        fail("needs OIIO's oiiotool on PATH to write the cameras into the headers")
    scene = bpy.context.scene
    name = opts["name"] or (os.path.splitext(os.path.basename(bpy.data.filepath))[0]
                            or scene.name)
    first, last = opts["frames"] or (scene.frame_start, scene.frame_end)
    if last < first:
        fail(f"empty frame range {first}-{last}")
    frames = range(first, last + 1)
    shots = shot_cameras(scene, opts["camera"], frames)
    render_settings(scene, opts["samples"], opts["indirect"])
    out_dir = os.path.abspath(opts["out"])
    os.makedirs(out_dir, exist_ok=True)
    face_cam, pano_cam = add_view_cameras(scene)
    n = opts["face_size"]
    latlong_size = (opts["latlong_width"], opts["latlong_width"] // 2)
    record = {"scene": name, "face_size": n, "latlong_width": latlong_size[0],
              "latlong_height": latlong_size[1], "spp": opts["samples"], "frames": []}
    json_path = os.path.join(out_dir, name + ".views.json")
    for f in frames:
        start = time.time()
        scene.frame_set(f)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        shot = shots[f].evaluated_get(depsgraph)
        shot_to_world = rigid(shot.matrix_world)
        entry = {"frame": f, "camera": shots[f].name,
                 "clip": [shot.data.clip_start, shot.data.clip_end], "views": {}}
        views = []
        for data in (face_cam.data, pano_cam.data):
            data.clip_start, data.clip_end = shot.data.clip_start, shot.data.clip_end
        if opts["faces"]:
            for face, columns in FACES.items():
                rotation = Matrix([[columns[j][i] for j in range(3)] for i in range(3)])
                face_cam.matrix_world = shot_to_world @ rotation.to_4x4()
                bpy.context.view_layer.update()
                depsgraph = bpy.context.evaluated_depsgraph_get()
                c2w = [list(row) for row in face_cam.matrix_world]
                proj = [list(row) for row in face_cam.evaluated_get(depsgraph).calc_matrix_camera(
                    depsgraph, x=n, y=n, scale_x=1.0, scale_y=1.0)]
                w2c = camera_matrices.world_to_camera(c2w)
                ndc = camera_matrices.world_to_ndc(c2w, proj)
                path = os.path.join(out_dir, f"{name}.{face}.{f:04d}.exr")
                views.append((render_view(scene, face_cam, (n, n), path), path, w2c, ndc))
                entry["views"][face] = {"camera_to_world_gl": c2w, "projection_gl": proj,
                                        "worldToCamera": w2c, "worldToNDC": ndc}
        if opts["latlong"]:
            pano_cam.matrix_world = shot_to_world
            bpy.context.view_layer.update()
            c2w = [list(row) for row in pano_cam.matrix_world]
            # Blender's camera space (looking along -z), not flipped as a pinhole's is.
            w2c = camera_matrices.flat_row_vector(camera_matrices.rigid_inverse(c2w))
            path = os.path.join(out_dir, f"{name}.latlong.{f:04d}.exr")
            views.append((render_view(scene, pano_cam, latlong_size, path), path, w2c, None))
            entry["views"]["latlong"] = {"camera_to_world_gl": c2w, "worldToCamera": w2c}
        add_headers(views)
        record["frames"].append(entry)
        with open(json_path, "w") as out:
            json.dump(record, out, indent=1)
        print(f"render_views.py: frame {f}: {len(entry['views'])} views in "
              f"{time.time() - start:.1f} s", flush=True)


main()
