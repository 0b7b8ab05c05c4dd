"""dqjulia for Blender: dual-quaternion Julia fractals as a live viewport preview, baked
OpenVDB volumes and meshes, and an OSL volume, all computed by the dqjulia core library.

Layout (one idea a module): native.py (ctypes bindings of the C ABI: the Python package's
python/dqjulia/_native.py, which the build copies into the zip), props.py (the
parameters on the object and the parameter file's JSON), slicing.py (the slice's 8-D axes),
animation.py (keyframes), core_state.py (what the core says about each object's parameters:
the state the other modules share), preview.py (the GLSL preview), jobs.py (work in a thread),
bakes.py (cache folder, objects from bakes), operators.py, variations.py (the Variations grid,
its thumbnails and picks), farm.py (farm tasks' bakes), panels.py,
osl.py, shaders/.
"""

bl_info = {
    "name": "DQ Julia",
    "author": "dqjulia",
    "version": (1, 0, 0),  # the build writes the project's VERSION here
    "blender": (3, 4, 0),
    "location": "View3D > Add > DQ Julia; View3D > Sidebar > DQ Julia; Properties > Object",
    "description": "Dual-quaternion Julia fractals: GLSL preview, OpenVDB volume and mesh bakes, OSL volume",
    "category": "Add Mesh",
    "doc_url": "",
}

import bpy
from bpy.props import StringProperty

from . import bakes, core_state, farm, jobs, native, operators, osl, panels, preview, props, variations


class DQJuliaPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    cache_dir: StringProperty(
        name="Cache folder",
        subtype="DIR_PATH",
        default="",
        description="Where volume bakes are written (VDB files). Empty: beside the .blend, in //dqjulia_cache/ "
        "(stored relative, so the project can move); an absolute folder is stored absolute",
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "cache_dir")
        try:
            layout.label(text="Bakes go to: %s" % bakes.cache_root(context))
        except ValueError as error:
            layout.label(
                text="Bakes go to: %s (beside the .blend once it is saved)" % bakes.chosen_cache(context),
                icon="INFO" if not bpy.data.filepath else "ERROR",
            )
            if bpy.data.filepath:
                layout.label(text=str(error), icon="ERROR")
        error = native.load_error()
        if error is None:
            layout.label(
                text="Library: dqjulia %s (%s)" % (native.version()[1], native.library_path()), icon="CHECKMARK"
            )
        else:
            box = layout.box()
            box.alert = True
            for line in panels.textwrap.wrap(error, 90):
                box.label(text=line)
        if not osl.available():
            layout.label(
                text="This Blender has no OSL: the OSL volume is unavailable (bakes and preview work).", icon="INFO"
            )


def register():
    bpy.utils.register_class(DQJuliaPreferences)
    props.register()
    core_state.register()
    operators.register()
    variations.register()
    farm.register()
    panels.register()
    osl.register()
    preview.register()
    bakes.register()


def unregister():
    bakes.unregister()
    jobs.cancel_all()
    for job in jobs.active_jobs():
        job.join(5.0)
    preview.unregister()
    osl.unregister()
    panels.unregister()
    farm.unregister()
    variations.unregister()
    operators.unregister()
    core_state.unregister()
    props.unregister()
    bpy.utils.unregister_class(DQJuliaPreferences)
