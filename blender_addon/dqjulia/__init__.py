"""dqjulia for Blender: dual-quaternion Julia fractals as a live viewport preview, baked
OpenVDB volumes and meshes, and an OSL volume, all computed by the dqjulia core library.

Layout (one idea a module): native.py (ctypes bindings of the C ABI: the Python package's
python/dqjulia/_native.py, which the build copies into the zip), props.py (the
parameters on the object and the parameter file's JSON), slicing.py (the slice's 8-D axes),
animation.py (keyframes), core_state.py (what the core says about each object's parameters:
the state the other modules share), preview.py (the GLSL preview), jobs.py (work in a thread),
bakes.py (cache folder, objects from bakes), operators.py, variations.py (the Variations grid,
its thumbnails and picks), assets.py (Mark as Asset, the preset asset library), farm.py (farm
tasks' bakes), studio.py (Frame Camera and Studio: a first render that shows the set),
panels.py, osl.py, shaders/.
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

import os

import bpy
from bpy.props import StringProperty

from . import (
    assets,
    bakes,
    core_state,
    farm,
    jobs,
    native,
    operators,
    osl,
    panels,
    preview,
    props,
    studio,
    variations,
)


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
        self.draw_asset_library(context, layout)
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

    @staticmethod
    def draw_asset_library(context, layout):
        """The preset asset library: where it goes, whether it is registered, the button."""
        box = layout.box()
        try:
            folder = assets.library_folder(create=False)
        except (OSError, ValueError) as error:
            box.label(text="Preset asset library: no user folder (%s)" % error, icon="ERROR")
            return
        library = assets.registered_library(context, folder)
        exists = os.path.isfile(os.path.join(folder, assets.LIBRARY_FILE))
        if library is not None and exists:
            box.label(text='Preset assets: the asset library "%s" (%s)' % (library.name, folder), icon="ASSET_MANAGER")
        else:
            box.label(
                text="The presets and the paper's figures as assets with thumbnails, in %s" % folder,
                icon="ASSET_MANAGER",
            )
        label = "Update Preset Asset Library" if library is not None and exists else "Add Preset Asset Library"
        box.operator(assets.DQJULIA_OT_preset_library.bl_idname, text=label)


def register():
    bpy.utils.register_class(DQJuliaPreferences)
    props.register()
    core_state.register()
    operators.register()
    variations.register()
    assets.register()
    farm.register()
    studio.register()
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
    studio.unregister()
    farm.unregister()
    assets.unregister()
    variations.unregister()
    operators.unregister()
    core_state.unregister()
    props.unregister()
    bpy.utils.unregister_class(DQJuliaPreferences)
