// SPDX-License-Identifier: GPL-3.0-or-later
//
// A Flamenco job type for the Caustics add-on: the frame range in chunks,
// one Blender task per chunk. Mode "bake" bakes the chunk's caustics into
// image sequences (caustic.bake_animation) and then, in the same Blender
// process, renders its frames with the scene's engine (EEVEE or Cycles);
// mode "caustics" renders the chunk with the add-on (caustic.render_animation).
// Chunks write the same files a single run would.
//
// Install: copy this file into the `scripts/` folder beside the Flamenco
// Manager and restart it. Workers need the add-on installed and the .blend,
// the output and the bake folder on shared storage.

const JOB_TYPE = {
    label: "Caustics",
    description: "Bake the caustics of each chunk, then render it; or render it with the Caustics add-on",
    settings: [
        { key: "mode", type: "string", required: true, default: "bake",
          choices: ["bake", "caustics"],
          description: "bake: bake the chunk's caustics, then render with the scene's engine; " +
                       "caustics: render with the Caustics add-on" },
        { key: "frames", type: "string", required: true,
          eval: "f'{C.scene.frame_start}-{C.scene.frame_end}'",
          description: "Frame range to render, such as '1-48'" },
        { key: "chunk_size", type: "int32", default: 4, visible: "submission",
          description: "Frames one Blender task renders" },
        { key: "render_output_path", type: "string", subtype: "file_path", required: true,
          eval: "C.scene.render.filepath", visible: "submission",
          description: "Output path of the frames, with # for the frame number (// is the .blend's folder)" },
        { key: "bake_folder", type: "string", subtype: "dir_path", default: "//caustic_bake/",
          visible: "submission", description: "Where mode 'bake' writes the baked caustics" },
        { key: "blendfile", type: "string", required: true, visible: "web",
          description: "Path of the .blend file to render" },
    ]
};

function compileJob(job) {
    const settings = job.settings;
    for (const chunk of frameChunker(settings.frames, settings.chunk_size)) {
        job.addTask(chunkTask(settings, chunk));
    }
}

// [first, last] frame of a chunk from frameChunker ("5-8", "5" or "5,7,9").
function chunkBounds(chunk) {
    const frames = chunk.split(/[-,]/).map((frame) => parseInt(frame, 10));
    return [Math.min(...frames), Math.max(...frames)];
}

// Python text for a single-quoted literal.
function pythonString(text) {
    return "'" + text.replace(/\\/g, "\\\\").replace(/'/g, "\\'") + "'";
}

function chunkTask(settings, chunk) {
    const [first, last] = chunkBounds(chunk);
    const range = `frame_start=${first}, frame_end=${last}`;
    const output = pythonString(settings.render_output_path);
    let args;
    if (settings.mode == "caustics") {
        args = ["--python-expr",
                `import bpy; bpy.ops.caustic.render_animation(filepath=${output}, ${range})`];
    } else {
        // Blender runs its arguments in order: the bake, then the render of the same frames.
        args = ["--python-expr",
                `import bpy; bpy.ops.caustic.bake_animation(directory=${pythonString(settings.bake_folder)}, ${range})`,
                "--render-output", settings.render_output_path,
                "--frame-start", String(first), "--frame-end", String(last),
                "--render-anim"];
    }
    const task = author.Task(`caustics-${chunk}`, "blender");
    task.addCommand(author.Command("blender-render", {
        exe: "{blender}",
        exeArgs: "{blenderArgs}",
        argsBefore: [],
        blendfile: settings.blendfile,
        args: args,
    }));
    return task;
}
