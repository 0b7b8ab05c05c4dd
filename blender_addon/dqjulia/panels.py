"""The UI: the same panels in the 3D view's sidebar (tab "DQ Julia") and in the object
properties. Problems are shown where the user looks: a missing or mismatched library, the
core's validation message for the current values, an empty slice and why, a bake's progress.
"""

import textwrap
import time

import bpy

from . import assets, bakes, core_state, jobs, native, operators, osl, preview, props, studio, variations


def _wrapped(layout, text, icon="NONE", alert=False, width=None):
    """A text in lines that fit the panel: as many characters a line as its region is wide
    (about 7 pixels a character at the default UI scale), so nothing is cut off."""
    if width is None:
        region = getattr(bpy.context, "region", None)
        scale = bpy.context.preferences.system.ui_scale if bpy.context.preferences else 1.0
        width = max(20, int((region.width if region else 400) / (7.0 * scale)) - 6)
    column = layout.column(align=True)
    column.alert = alert
    lines = textwrap.wrap(text, width) or [""]
    for index, line in enumerate(lines):
        column.label(text=line, icon=icon if index == 0 else "BLANK1")


QUATERNION_LABEL_FACTOR = 0.1  # the row label's share of the width: one letter
QUATERNION_FIELD_WIDTH = 64  # pixels (at UI scale 1) a field needs to show "-0.391"


def _constant(layout, context, settings):
    """The constant's two quaternions a and b under the heads s, i, j, k: as two rows when four
    fields fit across the region, else (the sidebar's default width) as two columns of four
    labelled fields, since a row of four there showed no more than "-0."."""
    region = context.region
    scale = context.preferences.system.ui_scale
    across = (region.width if region else 400) * (1.0 - QUATERNION_LABEL_FACTOR) - 30 * scale
    if across >= 4 * QUATERNION_FIELD_WIDTH * scale:
        column = layout.column(align=True)
        split = column.split(factor=QUATERNION_LABEL_FACTOR)
        split.label(text="")
        heads = split.row(align=True)
        for component in "sijk":
            heads.label(text=component)
        for name, label in (("c_a", "a"), ("c_b", "b")):
            split = column.split(factor=QUATERNION_LABEL_FACTOR)
            split.label(text=label)
            row = split.row(align=True)
            for index in range(4):
                row.prop(settings, name, index=index, text="")
        return
    row = layout.row()
    for name, label in (("c_a", "a"), ("c_b", "b")):
        column = row.column(align=True)
        column.label(text=label)
        for index, component in enumerate("sijk"):
            column.prop(settings, name, index=index, text=component)


class DQJULIA_MT_presets(bpy.types.Menu):
    bl_idname = "DQJULIA_MT_presets"
    bl_label = "Presets"

    def draw(self, _context):
        layout = self.layout
        for name in operators.preset_names():
            layout.operator(operators.DQJULIA_OT_load_preset.bl_idname, text=name).preset = name
        layout.separator()
        layout.operator(assets.DQJULIA_OT_preset_library.bl_idname, icon="ASSET_MANAGER")


class DQJULIA_UL_rotations(bpy.types.UIList):
    bl_idname = "DQJULIA_UL_rotations"

    def draw_item(self, _context, layout, _data, item, _icon, _active_data, _active_property, _index=0, _flt_flag=0):
        row = layout.row(align=True)
        row.prop(item, "first", text="")
        row.label(icon="FORWARD")
        row.prop(item, "second", text="")
        row.prop(item, "degrees", text="")


class _Base:
    bl_options = set()

    @classmethod
    def poll(cls, context):
        return operators.dqjulia_object(context) is not None


last_sidebar_draw = 0.0  # when the sidebar's main panel last drew (the screenshot script reads it)
last_grid_draw = 0.0  # when the Variations panel last drew its grid to the end (preview_test.py reads it)


class _MainPanel:
    bl_label = "DQ Julia"

    @classmethod
    def poll(cls, context):
        # Always in the sidebar (to offer "Add DQ Julia"); in the properties for DQ Julia objects.
        return cls.bl_space_type == "VIEW_3D" or operators.dqjulia_object(context) is not None

    def draw(self, context):
        global last_sidebar_draw
        if self.bl_space_type == "VIEW_3D":
            last_sidebar_draw = time.monotonic()
        layout = self.layout
        error = native.load_error()
        if error is not None:
            box = layout.box()
            _wrapped(box, "The dqjulia library cannot be used:", icon="ERROR", alert=True)
            _wrapped(box, error, alert=True)
            return
        obj = operators.dqjulia_object(context)
        if obj is None:
            layout.label(text="The active object is not a DQ Julia object.")
            layout.operator(operators.DQJULIA_OT_add.bl_idname, text="Add DQ Julia", icon="ADD")
            return
        s = obj.dqjulia
        row = layout.row(align=True)
        row.menu(DQJULIA_MT_presets.bl_idname, icon="PRESET")
        row.operator(operators.DQJULIA_OT_import_params.bl_idname, text="", icon="IMPORT")
        row.operator(operators.DQJULIA_OT_export_params.bl_idname, text="", icon="EXPORT")
        _asset_row(layout, obj)

        column = layout.column()
        column.prop(s, "variant")
        column.prop(s, "iterations")
        column.prop(s, "bailout")
        column.label(text="Constant c = a + b\u03b5:")
        _constant(column, context, s)

        state = core_state.state_for(obj)
        if state.error:
            box = layout.box()
            _wrapped(box, state.error, icon="ERROR", alert=True)
        elif state.empty_reason:
            box = layout.box()
            _wrapped(box, "Nothing to see: " + state.empty_reason, icon="INFO")
        elif state.inspect:
            box = layout.box()
            column = box.column(align=True)
            for part in ("real", "dual"):
                report = state.inspect[part]
                re_, im = report["complex"]
                inside = report["in_mandelbrot"]
                column.label(
                    text="%s ~ %.4g %+.4gi" % ("a" if part == "real" else "b", re_, im),
                    icon="CHECKMARK" if inside else "ERROR",
                )
                column.label(
                    text="in the Mandelbrot set" if inside else "outside the Mandelbrot set: dust", icon="BLANK1"
                )
            column.label(text="Inside: %.1f%% of the bounds" % (100.0 * state.inspect["inside_fraction"]))
        if preview.shader_error():
            _wrapped(layout.box(), preview.shader_error(), icon="ERROR", alert=True)
        for job in jobs.active_jobs(obj.name):
            row = layout.row()
            row.label(text=job.status_text(), icon="TIME")
            row.operator(operators.DQJULIA_OT_cancel_bakes.bl_idname, text="", icon="CANCEL")


def _asset_row(layout, obj):
    """Mark as Asset, or (an asset) whether its thumbnail still shows the object's values."""
    if obj.asset_data is None:
        layout.operator(assets.DQJULIA_OT_mark_asset.bl_idname, icon="ASSET_MANAGER")
    elif assets.thumbnail_stale(obj):
        row = layout.row(align=True)
        row.label(text="Asset: its thumbnail shows earlier values", icon="ASSET_MANAGER")
        row.operator(assets.DQJULIA_OT_mark_asset.bl_idname, text="Update", icon="FILE_REFRESH")
    else:
        layout.label(text="An asset (Asset Browser)", icon="ASSET_MANAGER")


def menu_mark_asset(self, context):
    """In Blender's own asset menus: Mark as Asset with the library's thumbnail."""
    if operators.dqjulia_object(context) is not None:
        self.layout.operator(
            assets.DQJULIA_OT_mark_asset.bl_idname, text="Mark as DQ Julia Asset", icon="ASSET_MANAGER"
        )


# Blender's asset menus that get the item above, where this Blender has them.
ASSET_MENUS = ("VIEW3D_MT_object_asset", "OUTLINER_MT_asset")


class _SlicePanel(_Base):
    bl_label = "Slice"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = operators.dqjulia_object(context).dqjulia
        layout = self.layout
        layout.prop(s, "axes_mode", expand=True)
        if s.axes_mode == "NAMES":
            row = layout.row(align=True)
            row.prop(s, "axis_x")
            row.prop(s, "axis_y")
            row.prop(s, "axis_z")
        else:
            for name in ("axis_x_vector", "axis_y_vector", "axis_z_vector"):
                layout.prop(s, name)
        layout.prop(s, "origin")
        layout.label(text="Rotations (applied in order):")
        row = layout.row()
        row.template_list(DQJULIA_UL_rotations.bl_idname, "", s, "rotations", s, "active_rotation", rows=2)
        column = row.column(align=True)
        add = column.operator(operators.DQJULIA_OT_collection_edit.bl_idname, text="", icon="ADD")
        add.collection, add.action = "rotations", "ADD"
        remove = column.operator(operators.DQJULIA_OT_collection_edit.bl_idname, text="", icon="REMOVE")
        remove.collection, remove.action, remove.index = "rotations", "REMOVE", s.active_rotation


class _VariationsPanel(_Base):
    """A grid of variations of the object (variations.py): strength, locks, Refresh, Back and
    Forward, and the thumbnails; a click applies one (or applies it to a copy)."""

    bl_label = "Variations"

    def draw(self, context):
        obj = operators.dqjulia_object(context)
        s = obj.dqjulia
        layout = self.layout
        why = variations.unavailable()
        if why is not None:
            _wrapped(layout, why, icon="ERROR", alert=True)
            return
        column = layout.column(align=True)
        column.prop(s, "variation_strength", slider=True)
        column.label(text=variations.strength_words(s.variation_strength))
        layout.label(text="Keep as they are:")
        flow = layout.grid_flow(columns=3, even_columns=True, align=True)
        for name, _label, _description in props.VARIATION_GROUP_ITEMS:
            flow.prop_enum(s, "variation_locks", name)
        grid = variations.grid_for(obj)
        history = variations.history_for(obj)
        row = layout.row(align=True)
        refresh = row.operator(
            variations.DQJULIA_OT_variations_refresh.bl_idname,
            text="Refresh" if grid is not None else "Show Variations",
            icon="FILE_REFRESH",
        )
        refresh.next_seed = grid is not None
        for step, icon in ((-1, "BACK"), (1, "FORWARD")):
            button = row.row(align=True)
            button.enabled = history is not None and history.can_step(step)
            button.operator(variations.DQJULIA_OT_variations_history.bl_idname, text="", icon=icon).step = step
        if grid is None:
            return
        if grid.running:
            row = layout.row()
            row.label(
                text="Making variations: %d of %d (Esc stops)" % (len(grid.thumbnails), variations.COUNT),
                icon="TIME",
            )
        if grid.message:
            _wrapped(layout.box(), grid.message, icon="ERROR" if not grid.thumbnails else "INFO", alert=True)
        elif variations.stale(obj, grid):
            _wrapped(layout, "The object changed since: Refresh varies its current values.", icon="INFO")
        self._thumbnails(context, layout, grid)

    @staticmethod
    def _thumbnails(context, layout, grid):
        if not grid.thumbnails and not grid.running:
            return
        region = context.region
        ui_scale = context.preferences.system.ui_scale
        width = (region.width if region else 300) - 40 * ui_scale
        scale = max(2.0, width / 3.0 / (20.0 * ui_scale))
        flow = layout.grid_flow(row_major=True, columns=3, even_columns=True, even_rows=True, align=False)
        failed = []
        for index in range(variations.COUNT):
            column = flow.column(align=True)
            preview = variations.preview_of(grid, index)
            column.template_icon(
                icon_value=preview.icon_id if preview is not None else variations.placeholder_icon(), scale=scale
            )
            error = variations.slot_error(grid, index)
            if error:
                failed.append("%d: %s" % (index + 1, error))
            row = column.row(align=True)
            row.enabled = preview is not None
            apply = row.operator(variations.DQJULIA_OT_variation_apply.bl_idname, text=str(index + 1))
            apply.index = index
            copy = row.operator(variations.DQJULIA_OT_variation_apply.bl_idname, text="", icon="DUPLICATE")
            copy.index, copy.copy = index, True
        for line in failed:
            _wrapped(layout, "No thumbnail for " + line, icon="ERROR", alert=True)
        if grid.summary:
            _wrapped(layout, grid.summary)
        global last_grid_draw
        last_grid_draw = time.monotonic()


class _BoundsPanel(_Base):
    bl_label = "Bounds"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        obj = operators.dqjulia_object(context)
        s = obj.dqjulia
        layout = self.layout
        layout.prop(s, "bounds_auto")
        column = layout.column()
        column.enabled = not s.bounds_auto
        column.prop(s, "bounds_center")
        column.prop(s, "bounds_radius")
        state = core_state.state_for(obj)
        if state.bounds:
            center, radius, clipped = state.bounds
            layout.label(
                text="Sphere: centre (%.3g, %.3g, %.3g), radius %.4g%s"
                % (center[0], center[1], center[2], radius, " (clips an extrusion)" if clipped else "")
            )


class _PreviewPanel(_Base):
    bl_label = "Viewport Preview"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = operators.dqjulia_object(context).dqjulia
        layout = self.layout
        row = layout.row()
        row.prop(s, "show_preview")
        row.prop(s, "show_bounds")
        column = layout.column()
        column.enabled = s.show_preview
        column.prop(s, "preview_resolution")
        column.prop(s, "preview_max_steps")
        column.prop(s, "preview_detail")
        column.prop(s, "step_factor")
        column.prop(s, "max_step")
        column.prop(s, "coloring")
        if s.coloring == "solid":
            column.prop(s, "color")


class _BakePanel(_Base):
    bl_label = "Bake"

    def draw(self, context):
        obj = operators.dqjulia_object(context)
        s = obj.dqjulia
        layout = self.layout
        layout.prop(s, "bake_resolution")
        flow = layout.grid_flow(columns=3, even_columns=True, align=True)
        for name, _label, _description in props.GRID_ITEMS:
            flow.prop_enum(s, "bake_grids", name)
        props.draw_fields(layout, s, props.section_keys("bake", exclude=("bake.resolution",)))
        layout.prop(s, "bake_bounds_auto")
        if not s.bake_bounds_auto:
            layout.prop(s, "bake_bounds_min")
            layout.prop(s, "bake_bounds_max")
        if native.load_error() is None and not native.has("dqj_bake_vdb"):
            _wrapped(
                layout, "This dqjulia library cannot bake (built without OpenVDB baking).", icon="ERROR", alert=True
            )
        if bakes.renders_nothing(context.scene.objects, obj):
            _wrapped(
                layout.box(),
                "Renders (F12) show nothing yet: the preview is for the viewport. Bake a volume "
                "or a mesh here%s."
                % (", or add an OSL volume below" if osl.available() else " (this Blender has no OSL volume)"),
                icon="INFO",
            )
        for baked, path in bakes.missing_bakes(obj.children):
            _wrapped(
                layout.box(),
                "%s renders empty: its bake file %s is missing. Bake again, or find it with "
                "File > External Data > Find Missing Files." % (baked.name, path),
                icon="ERROR",
                alert=True,
            )
        try:
            bakes.cache_root(context)
        except ValueError as error:
            _wrapped(layout, "Volumes: " + str(error), icon="INFO")
        column = layout.column(align=True)
        column.operator(operators.DQJULIA_OT_bake_volume.bl_idname, icon="OUTLINER_OB_VOLUME")
        column.operator(operators.DQJULIA_OT_bake_mesh.bl_idname, icon="MESH_ICOSPHERE")
        scene = context.scene
        column.operator(
            operators.DQJULIA_OT_bake_sequence.bl_idname,
            icon="RENDER_ANIMATION",
            text="Bake Sequence %d-%d" % (scene.frame_start, scene.frame_end),
        )
        for job in jobs.active_jobs(obj.name):
            row = layout.row()
            row.label(text=job.status_text(), icon="TIME")
            row.operator(operators.DQJULIA_OT_cancel_bakes.bl_idname, text="Cancel", icon="CANCEL")
        layout.label(text="Esc cancels a running bake.", icon="INFO")
        layout.prop(s, "volume_look", expand=True)
        row = layout.row(align=True)  # the first render: the camera on the set, lights that show its form
        row.operator(studio.DQJULIA_OT_frame_camera.bl_idname, icon="CAMERA_DATA")
        row.operator(studio.DQJULIA_OT_studio.bl_idname, icon="LIGHT_SUN")


class _OslPanel(_Base):
    bl_label = "OSL Volume (Cycles)"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, _context):
        layout = self.layout
        if not osl.available():
            _wrapped(layout, osl.UNAVAILABLE_MESSAGE, icon="INFO")
        row = layout.row(align=True)
        row.enabled = osl.available()
        row.operator(operators.DQJULIA_OT_add_osl_volume.bl_idname, icon="NODE_MATERIAL")
        layout.operator(operators.DQJULIA_OT_open_osl_text.bl_idname, icon="TEXT")


class _ShadingPanel(_Base):
    """The material and lights the preview shades with (and the core's renderer). The settings
    only `dqjulia render` uses (camera, image size, samples, output: the schema's image_only
    keys) are not shown; they stay in the object and in the exported parameter file."""

    bl_label = "Shading"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = operators.dqjulia_object(context).dqjulia
        layout = self.layout
        column = layout.column()
        column.prop(s, "coloring")
        column.prop(s, "color")
        row = column.row()
        row.label(text="Palette")
        add = row.operator(operators.DQJULIA_OT_collection_edit.bl_idname, text="", icon="ADD")
        add.collection, add.action = "palette", "ADD"
        remove = row.operator(operators.DQJULIA_OT_collection_edit.bl_idname, text="", icon="REMOVE")
        remove.collection, remove.action = "palette", "REMOVE"
        for entry in s.palette:
            column.prop(entry, "color", text="")
        props.draw_fields(
            column,
            s,
            [
                key
                for key in props.section_keys("material", exclude=("material.color", "material.coloring"))
                if not props.FIELDS[key].get("image_only")
            ],
        )
        row = column.row()
        row.label(text="Lights")
        add = row.operator(operators.DQJULIA_OT_collection_edit.bl_idname, text="", icon="ADD")
        add.collection, add.action = "lights", "ADD"
        remove = row.operator(operators.DQJULIA_OT_collection_edit.bl_idname, text="", icon="REMOVE")
        remove.collection, remove.action = "lights", "REMOVE"
        for light in s.lights:
            box = column.box()
            box.prop(light, "direction")
            row = box.row()
            row.prop(light, "color", text="")
            row.prop(light, "intensity")
        column.prop(s, "description")


def _make_panels():
    """The panel classes for both places: the sidebar and the object properties."""
    spaces = {
        "VIEW3D": {"bl_space_type": "VIEW_3D", "bl_region_type": "UI", "bl_category": "DQ Julia"},
        "OBJECT": {"bl_space_type": "PROPERTIES", "bl_region_type": "WINDOW", "bl_context": "object"},
    }
    classes = []
    for prefix, placement in spaces.items():
        main_id = "%s_PT_dqjulia" % prefix
        main = type(main_id, (_MainPanel, bpy.types.Panel), dict(placement, bl_idname=main_id))
        classes.append(main)
        for base in (_VariationsPanel, _SlicePanel, _BoundsPanel, _PreviewPanel, _BakePanel, _OslPanel, _ShadingPanel):
            name = "%s_PT_dqjulia_%s" % (prefix, base.__name__.strip("_").replace("Panel", "").lower())
            attributes = dict(placement, bl_idname=name, bl_parent_id=main_id)
            classes.append(type(name, (base, bpy.types.Panel), attributes))
    return classes


CLASSES = [DQJULIA_MT_presets, DQJULIA_UL_rotations] + _make_panels()


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    for name in ASSET_MENUS:
        menu = getattr(bpy.types, name, None)
        if menu is not None:
            menu.append(menu_mark_asset)


def unregister():
    for name in ASSET_MENUS:
        menu = getattr(bpy.types, name, None)
        if menu is not None:
            menu.remove(menu_mark_asset)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
