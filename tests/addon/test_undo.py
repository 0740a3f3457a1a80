"""Results survive undo and redo: the operators that write images push an
undo step, as a click in the UI does, and the images keep their pixels.
Scripts call operators without an undo push unless asked, so these tests
ask ('EXEC_DEFAULT', True), as the sidebar's buttons do."""

import bpy
import numpy as np
import pytest

import blender_scenes as scenes


def move_then_undo(ob) -> None:
    """What a user does after a render: move an object, then Ctrl-Z."""
    ob.location.x += 0.25
    bpy.ops.ed.undo_push(message="Move")
    assert bpy.ops.ed.undo() == {'FINISHED'}


def test_render_survives_undo_and_redo_with_its_pixels():
    parts = scenes.ball_lens_scene(32, 24, lamp_rays=20_000, segments=32, rings=16)
    bpy.ops.ed.undo_push(message="Scene")
    assert bpy.ops.caustic.render('EXEC_DEFAULT', True) == {'FINISHED'}
    rendered = scenes.pixels_of("Caustic Render")
    assert rendered[..., :3].max() > 1.0

    move_then_undo(parts["ball"])
    assert bpy.data.objects["Ball"].location.x == 0.0
    assert np.array_equal(scenes.pixels_of("Caustic Render"), rendered)
    assert bpy.ops.ed.redo() == {'FINISHED'}
    assert bpy.data.objects["Ball"].location.x == 0.25
    assert np.array_equal(scenes.pixels_of("Caustic Render"), rendered)


def test_a_second_render_replaces_the_pixels_and_undo_brings_the_first_back():
    parts = scenes.ball_lens_scene(32, 24, lamp_rays=20_000, segments=32, rings=16)
    bpy.ops.ed.undo_push(message="Scene")
    bpy.ops.caustic.render('EXEC_DEFAULT', True)
    first = scenes.pixels_of("Caustic Render")
    parts["lamp"].data.energy *= 2.0
    bpy.ops.ed.undo_push(message="Brighter")
    bpy.ops.caustic.render('EXEC_DEFAULT', True)
    second = scenes.pixels_of("Caustic Render")
    assert np.allclose(second[..., :3], 2.0 * first[..., :3], rtol=1e-4, atol=1e-6)
    bpy.ops.ed.undo()
    bpy.ops.ed.undo()
    assert np.array_equal(scenes.pixels_of("Caustic Render"), first)


def test_cycles_reference_survives_undo_with_its_pixels():
    parts = scenes.ball_lens_scene(24, 18, lamp_rays=10_000, segments=32, rings=16)
    bpy.context.scene.caustic.cycles_samples = 4
    bpy.ops.ed.undo_push(message="Scene")
    assert bpy.ops.caustic.compare_cycles('EXEC_DEFAULT', True) == {'FINISHED'}
    images = {name: scenes.pixels_of(name) for name in ("Caustic Render", "Cycles Reference", "Difference")}
    assert images["Cycles Reference"][..., :3].max() > 0.1

    move_then_undo(parts["ball"])
    for name, pixels in images.items():
        assert np.array_equal(scenes.pixels_of(name), pixels), name


def test_bake_and_compare_wait_while_a_render_runs(addon):
    scenes.ball_lens_scene(24, 18, lamp_rays=10_000, segments=32, rings=16)
    render = addon.operators.engine_run.EngineOperator
    render.running = True
    try:
        for operator in (bpy.ops.caustic.bake, bpy.ops.caustic.compare_cycles, bpy.ops.caustic.render):
            assert not operator.poll()
            with pytest.raises(RuntimeError, match="A caustic render is running"):
                operator()
    finally:
        render.running = False
    assert bpy.ops.caustic.bake.poll() and bpy.ops.caustic.compare_cycles.poll()


@pytest.mark.parametrize("operator", ["bake", "render_image_with_caustics"])
def test_a_bake_survives_undo_with_its_pixels_and_its_nodes(operator):
    parts = scenes.ball_lens_scene(24, 18, lamp_rays=10_000, segments=32, rings=16)
    bpy.context.scene.render.engine = 'CYCLES'
    bpy.context.scene.cycles.samples = 1
    bpy.ops.ed.undo_push(message="Scene")
    assert getattr(bpy.ops.caustic, operator)('EXEC_DEFAULT', True) == {'FINISHED'}
    baked = scenes.pixels_of("Caustic Map Floor")
    assert baked[..., :3].max() > 0.0

    move_then_undo(parts["ball"])
    assert np.array_equal(scenes.pixels_of("Caustic Map Floor"), baked)
    assert "Caustic Bake Floor" in bpy.data.node_groups
