# Renders a volume baked by `dqjulia bake` with Blender's Cycles, for pictures of baked results.
#
#   dqjulia bake -r 256 --grids surface,density,color -o out/fractal.vdb
#   blender -b --factory-startup --python-exit-code 1 --python scripts/render_vdb_in_blender.py -- \
#       out/fractal.vdb out/fractal-blender.png [--size 640x480] [--samples 64] [--density 60]
#
# The volume is imported as it is (slice coordinates; turned so the slice's y axis points up, as
# in `dqjulia render`), shaded with a Principled Volume whose density is the "density" grid
# times --density and whose colour is the "color" grid when the file has one. A sun and a sky
# colour light it; the camera looks from the direction `dqjulia render` uses by default.
# CPU only, no denoiser (neither is needed in a headless build).
import argparse
import math
import sys

import bpy
from mathutils import Vector


def parse(argv):
    parser = argparse.ArgumentParser(prog="render_vdb_in_blender.py")
    parser.add_argument("vdb")
    parser.add_argument("png")
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--density", type=float, default=60.0, help="density multiplier (per unit length)")
    return parser.parse_args(argv)


def main(args):
    width, height = (int(part) for part in args.size.split("x"))
    scene = bpy.context.scene
    for obj in list(scene.objects):  # the factory startup's cube, light and camera
        bpy.data.objects.remove(obj)

    volume = bpy.data.volumes.new("dqjulia")
    volume.filepath = bpy.path.abspath(args.vdb)
    if not volume.grids.load():
        raise SystemExit(f"cannot load {args.vdb}: {volume.grids.error_message}")
    grids = {grid.name for grid in volume.grids}
    if "density" not in grids:
        raise SystemExit(f"{args.vdb} has no 'density' grid (found {sorted(grids)}); bake with --grids ...,density")
    fractal = bpy.data.objects.new("dqjulia", volume)
    fractal.rotation_euler = (math.radians(90.0), 0.0, 0.0)  # slice y -> Blender z (up)
    scene.collection.objects.link(fractal)

    material = bpy.data.materials.new("dqjulia volume")
    if bpy.app.version < (5, 0, 0):  # 5.0: always node-based, use_nodes is deprecated
        material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    shader = nodes.new("ShaderNodeVolumePrincipled")
    shader.inputs["Density"].default_value = args.density
    shader.inputs["Density Attribute"].default_value = "density"
    shader.inputs["Anisotropy"].default_value = 0.2
    if "color" in grids:
        attribute = nodes.new("ShaderNodeAttribute")
        attribute.attribute_name = "color"
        links.new(attribute.outputs["Color"], shader.inputs["Color"])
    else:
        shader.inputs["Color"].default_value = (0.85, 0.62, 0.35, 1.0)
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(shader.outputs["Volume"], output.inputs["Volume"])
    volume.materials.append(material)

    # Frame the volume's bounding sphere from the renderer's default direction (0.55, 0.45, 1).
    bpy.context.view_layer.update()
    corners = [fractal.matrix_world @ Vector(corner) for corner in fractal.bound_box]
    centre = sum(corners, Vector()) / 8.0
    radius = max((corner - centre).length for corner in corners) * 0.72
    direction = Vector((0.55, -1.0, 0.45)).normalized()  # (0.55, 0.45, 1) turned like the volume
    camera_data = bpy.data.cameras.new("camera")
    camera_data.angle = math.radians(40.0)
    camera = bpy.data.objects.new("camera", camera_data)
    camera.location = centre + direction * (radius / math.sin(camera_data.angle / 2.0))
    camera.rotation_euler = (-direction).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera

    sun_data = bpy.data.lights.new("sun", type="SUN")
    sun_data.energy = 4.0
    sun_data.angle = math.radians(8.0)
    sun = bpy.data.objects.new("sun", sun_data)
    sun.rotation_euler = Vector((0.6, -0.7, 0.8)).to_track_quat("Z", "Y").to_euler()
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("sky")
    if bpy.app.version < (5, 0, 0):
        world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.30, 0.36, 0.45, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.world = world

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.cycles.volume_bounces = 1
    scene.cycles.volume_step_rate = 1.0
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.view_settings.view_transform = "Filmic"
    scene.render.filepath = bpy.path.abspath(args.png)
    bpy.ops.render.render(write_still=True)
    print(f"render_vdb_in_blender: wrote {args.png}")


main(parse(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []))
