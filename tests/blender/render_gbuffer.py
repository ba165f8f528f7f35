"""Three frames of G-buffer as stock Blender writes them, for the CLI tests on real Blender output.

Usage (Blender 3.4, headless):
  blender -b --factory-startup --python-exit-code 1 -P tests/blender/render_gbuffer.py -- OUTDIR

Builds a corner of a room (floor, two walls) with three boxes under a sun and a dim grey world,
all Diffuse BSDF, and a perspective camera that looks down and across it with a lens shift,
moving over frames 1-3. Renders OUTDIR/corner.0001.exr .. corner.0003.exr at 64x36: Cycles
CPU, 8 samples, no adaptive sampling, no denoising, a 0.01-pixel filter (every sample at the
pixel centre, so the data passes are the exact values there), multilayer 32-bit float ZIP EXR,
view layer "ViewLayer" with Combined, Depth, Normal, Position, DiffCol, DiffDir, DiffInd, Emit
and Vector. The files are left as Blender writes them: their headers hold no camera.

Writes OUTDIR/camera.json, the true camera per frame in ssgi's --camera sidecar format
(ssgi-cameras(7)): worldToCamera and worldToNDC from Blender's own camera-to-world and
projection matrices (which include the lens shift), by the conversion the accuracy training set
uses (../accuracy/training/camera_matrices.py). Lens, sensor and shift are there for reading;
no hfov_deg, which the sidecar would take as a centred camera's.
"""

import json
import math
import os
import sys

import bpy
from mathutils import Quaternion, Vector

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "accuracy",
                                "training"))
import camera_matrices  # noqa: E402

WIDTH, HEIGHT = 64, 36
FRAMES = 3
SAMPLES = 8
NAME = "corner"
LENS_MM = 24.0
SENSOR_WIDTH_MM = 36.0
# A lens shift moves the principal point off the image centre, in units of the larger image
# dimension: to pixel (32 - 0.05 * 64, 18 - 0.03 * 64) = (28.8, 16.08), y down.
SHIFT_X, SHIFT_Y = 0.05, -0.03
# Camera position, look-at target and roll (degrees about the view direction) per key frame.
CAMERA_KEYS = [(1, (2.6, -3.4, 1.9), (-0.4, 0.9, 0.5), 4.0),
               (FRAMES, (3.1, -2.9, 2.0), (-0.5, 1.1, 0.45), 7.0)]


def material(name, rgb):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nodes = m.node_tree.nodes
    nodes.clear()
    shader = nodes.new("ShaderNodeBsdfDiffuse")
    shader.inputs["Color"].default_value = (*rgb, 1.0)
    shader.inputs["Roughness"].default_value = 0.0
    out = nodes.new("ShaderNodeOutputMaterial")
    m.node_tree.links.new(shader.outputs["BSDF"], out.inputs["Surface"])
    return m


def box_span(name, lo, hi, rgb, rotation_z=0.0):
    """A box from corner lo to corner hi, turned by rotation_z radians about its vertical axis."""
    center = [(a + b) / 2 for a, b in zip(lo, hi)]
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=center, rotation=(0.0, 0.0, rotation_z))
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = [abs(b - a) for a, b in zip(lo, hi)]
    obj.data.materials.append(material(name, rgb))
    return obj


def scene_geometry():
    box_span("Floor", (-2.0, -4.0, -0.2), (4.0, 2.2, 0.0), (0.6, 0.55, 0.5))
    box_span("Back wall", (-2.2, 2.0, 0.0), (4.0, 2.2, 2.6), (0.75, 0.75, 0.72))
    box_span("Left wall", (-2.2, -4.0, 0.0), (-2.0, 2.0, 2.6), (0.65, 0.15, 0.1))
    box_span("Crate", (-1.4, 0.6, 0.0), (-0.4, 1.6, 1.0), (0.2, 0.5, 0.25), rotation_z=0.3)
    box_span("Block", (0.4, -0.2, 0.0), (1.2, 0.6, 0.6), (0.25, 0.35, 0.7))
    box_span("Pillar", (1.8, 1.2, 0.0), (2.3, 1.7, 1.8), (0.8, 0.7, 0.3))


def lights():
    sun = bpy.data.lights.new("Sun", "SUN")
    sun.energy = 3.0
    sun.angle = math.radians(1.0)
    obj = bpy.data.objects.new("Sun", sun)
    bpy.context.scene.collection.objects.link(obj)
    to_sun = Vector((0.5, -0.6, 0.8)).normalized()
    obj.rotation_euler = (-to_sun).to_track_quat("-Z", "Y").to_euler()
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.3, 0.35, 0.45, 1.0)
    background.inputs["Strength"].default_value = 0.5
    bpy.context.scene.world = world


def camera():
    data = bpy.data.cameras.new("Cam")
    data.lens = LENS_MM
    data.sensor_width = SENSOR_WIDTH_MM
    data.sensor_fit = "AUTO"
    data.shift_x = SHIFT_X
    data.shift_y = SHIFT_Y
    data.clip_start = 0.05
    data.clip_end = 100.0
    cam = bpy.data.objects.new("Cam", data)
    bpy.context.scene.collection.objects.link(cam)
    bpy.context.scene.camera = cam
    for frame, location, target, roll_deg in CAMERA_KEYS:
        q = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y")
        cam.location = location
        cam.rotation_euler = (q @ Quaternion((0.0, 0.0, 1.0), math.radians(roll_deg))).to_euler()
        cam.keyframe_insert("location", frame=frame)
        cam.keyframe_insert("rotation_euler", frame=frame)
    for fc in cam.animation_data.action.fcurves:
        for k in fc.keyframe_points:
            k.interpolation = "LINEAR"
    return cam


def render_settings(scene):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.film_filter_width = 0.01
    scene.render.use_motion_blur = False  # the Vector pass needs it off
    scene.render.resolution_x = WIDTH
    scene.render.resolution_y = HEIGHT
    scene.render.resolution_percentage = 100
    scene.frame_start = 1
    scene.frame_end = FRAMES
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    layer = scene.view_layers[0]
    layer.name = "ViewLayer"
    for p in ("combined", "z", "normal", "position", "diffuse_color", "diffuse_direct",
              "diffuse_indirect", "emit", "vector"):
        setattr(layer, "use_pass_" + p, True)


def camera_json(scene):
    """The sidecar: per frame, the matrices of the camera Blender renders that frame with."""
    cam = scene.camera
    out = {"scene": NAME, "width": WIDTH, "height": HEIGHT, "spp": SAMPLES,
           "lens_mm": LENS_MM, "sensor_width_mm": SENSOR_WIDTH_MM,
           "shift_x": SHIFT_X, "shift_y": SHIFT_Y, "frames": []}
    for f in range(1, FRAMES + 1):
        scene.frame_set(f)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        c2w = [list(row) for row in cam.matrix_world]
        proj = [list(row) for row in
                cam.calc_matrix_camera(depsgraph, x=WIDTH, y=HEIGHT, scale_x=1.0, scale_y=1.0)]
        out["frames"].append({
            "frame": f,
            "camera_to_world_gl": c2w,
            "projection_gl": proj,
            "worldToCamera": camera_matrices.world_to_camera(c2w),
            "worldToNDC": camera_matrices.world_to_ndc(c2w, proj),
        })
    scene.frame_set(1)
    return out


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 1:
        raise SystemExit("render_gbuffer.py: give the output directory (see the usage at the top)")
    out_dir = os.path.abspath(argv[0])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    render_settings(scene)
    scene_geometry()
    lights()
    camera()
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "camera.json"), "w") as f:
        json.dump(camera_json(scene), f, indent=1)
    scene.render.filepath = os.path.join(out_dir, NAME + ".####")
    bpy.ops.render.render(animation=True)


main()
