"""CAUSTIC_OT_add_paper_scene: one of the paper's scenes (section 4), added
to the current scene from the engine's own builders (its shapes and paper
layout), so that benchmarks/paper.py and Blender render the same geometry."""

import math

import bpy
import numpy as np
from mathutils import Vector

from ..caustic_addon import paper, shapes
from ..writeback.paper_scene import blender_mesh, node_material

COLLECTION = "Paper scene"
# key -> (label, IOR, description)
INDICES = {
    'WATER': ("Water", paper.INDICES["water"], "Water, n = 1.33"),
    'ZIRCONIA': ("Cubic Zirconia", paper.INDICES["cubic zirconia"], "Cubic zirconia, n = 1.9"),
    'DIAMOND': ("Diamond", paper.INDICES["diamond"], "Diamond, n = 2.41"),
}
SHAPE_ITEMS = [
    ('ROUND', "Round Base", "A sphere (radius 0.5 m): the paper's table 1"),
    ('FLAT', "Flat Base", "A cylinder (radius 0.5 m, 0.8 m tall): the paper's table 2"),
    ('POINTED', "Pointed Base", "A cone (radius 0.5 m, 1 m tall), point down: the paper's table 3"),
]


class CAUSTIC_OT_add_paper_scene(bpy.types.Operator):
    """Add one of the paper's scenes at the 3D cursor, in a new collection:
    a glass object of the chosen base and index over a 16 m diffuse floor
    (albedo 0.8), a 10 W point lamp (a Paper preset's lamp energy 10 makes
    it the paper's 100 W) and the paper's 40 degree camera. Nothing already
    in the file is changed; the new camera becomes the scene's camera only
    if the scene has none"""

    bl_idname = "caustic.add_paper_scene"
    bl_label = "Add Paper Scene"
    bl_options = {'REGISTER', 'UNDO'}

    shape: bpy.props.EnumProperty(name="Base", items=SHAPE_ITEMS, default='ROUND')
    ior_preset: bpy.props.EnumProperty(
        name="Medium", default='WATER',
        items=[(key, label, description) for key, (label, _, description) in INDICES.items()]
        + [('CUSTOM', "Custom", "The index of refraction typed below")])
    ior: bpy.props.FloatProperty(name="IOR", description="Index of refraction for a custom medium",
                                 default=1.5, soft_min=1.0, soft_max=3.0, precision=3)
    raised: bpy.props.BoolProperty(name="Raised", description="The paper's raised position: 1 m above the floor")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "shape")
        layout.prop(self, "ior_preset")
        sub = layout.row()
        sub.active = self.ior_preset == 'CUSTOM'
        sub.prop(self, "ior")
        layout.prop(self, "raised")

    def execute(self, context):
        label, ior = ("Glass", self.ior) if self.ior_preset == 'CUSTOM' else INDICES[self.ior_preset][:2]
        if not (math.isfinite(ior) and ior > 0):
            self.report({'ERROR'}, f"Add Paper Scene: IOR must be a positive number (got {ior:g})")
            return {'CANCELLED'}
        scene = context.scene
        cursor = np.array(scene.cursor.location, dtype=np.float64)
        collection = bpy.data.collections.new(COLLECTION)
        scene.collection.children.link(collection)

        def add(name, data, location):
            ob = bpy.data.objects.new(name, data)
            ob.location = location
            collection.objects.link(ob)
            return ob

        floor = add("Floor", blender_mesh("Floor", shapes.plane(paper.FLOOR_SIZE), np.zeros(3)), cursor)
        floor.data.materials.append(node_material("Paper Floor", 'ShaderNodeBsdfDiffuse',
                                                  Color=(*[paper.FLOOR_ALBEDO] * 3, 1.0)))
        mesh = paper.glass(self.shape.lower(), paper.RAISED if self.raised else 0.0)
        origin = np.array([0.0, 0.0, mesh.vertices[:, 2].min()])
        glass = add(self.shape.title(), blender_mesh(self.shape.title(), mesh, origin), cursor + origin)
        glass.data.materials.append(node_material(f"{label} {ior:g}", 'ShaderNodeBsdfGlass', IOR=ior,
                                                  Roughness=0.0))

        light = bpy.data.lights.new("Lamp", 'POINT')
        light.energy = paper.LAMP_POWER
        light.shadow_soft_size = 0.0
        add("Lamp", light, cursor + paper.LAMP_POSITION)
        data = bpy.data.cameras.new("Camera")
        data.sensor_fit, data.angle = 'HORIZONTAL', math.radians(paper.FOV)
        camera = add("Camera", data, cursor + paper.EYE)
        camera.rotation_euler = (Vector(paper.TARGET) - Vector(paper.EYE)).to_track_quat(
            '-Z', 'Y').to_euler()
        if scene.camera is None:
            scene.camera = camera
        context.view_layer.objects.active = glass
        glass.select_set(True)
        self.report({'INFO'}, f"Added {collection.name}: {glass.name}, n = {ior:g}"
                    + ("" if scene.camera is camera else f"; the scene camera stays '{scene.camera.name}'"))
        return {'FINISHED'}
