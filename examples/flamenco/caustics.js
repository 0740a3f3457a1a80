// SPDX-License-Identifier: GPL-3.0-or-later
//
// A Flamenco 3.8 job type for the Caustics add-on: the frames in chunks,
// one Blender task per chunk. Mode "bake" bakes the chunk's caustics into
// image sequences (caustic.bake_animation) and then, in the same Blender
// process, renders its frames with the scene's engine (EEVEE or Cycles);
// mode "caustics" renders the chunk with the add-on
// (caustic.render_animation). Chunks write the same files one run would.
//
// Paths travel as whole arguments after `--`, never inside the Python
// expression, so that the Manager's two-way path variables map them for
// each Worker's platform (it rewrites the separators of any argument that
// holds a path variable).
//
// Install: copy this file into the `scripts/` folder beside the Flamenco
// Manager and restart it. Workers need the add-on installed, and the
// .blend, the output and the bake folder on shared storage
// (docs/batch.md).

const MODES = ["bake", "caustics"];

const JOB_TYPE = {
    label: "Caustics",
    description: "Bake the caustics of each chunk, then render it; or render it with the Caustics add-on",
    settings: [
        { key: "mode", type: "string", required: true, default: "bake", choices: MODES,
          description: "bake: bake the chunk's caustics, then render with the scene's engine; " +
                       "caustics: render with the Caustics add-on" },
        { key: "frames", type: "string", required: true,
          eval: "f'{C.scene.frame_start}-{C.scene.frame_end}'",
          evalInfo: { showLinkButton: true, description: "Scene frame range" },
          description: "Frames to render, such as '1-48' or '1,3,5-6'" },
        { key: "chunk_size", type: "int32", default: 4, propargs: { min: 1 }, visible: "submission",
          description: "Frames one Blender task renders" },
        { key: "render_output_path", type: "string", subtype: "file_path", required: true,
          eval: "C.scene.render.filepath", visible: "submission",
          description: "Output path of the frames, with # for the frame number (// is the .blend's folder)" },
        { key: "bake_folder", type: "string", subtype: "dir_path", default: "//caustic_bake/",
          visible: "submission", description: "Where mode 'bake' writes the baked caustics" },
        // The add-on's settings a farm run depends on, shown with the job.
        { key: "light_rays", type: "int32", eval: "C.scene.caustic.lamp_rays", visible: "web",
          description: "The scene's Light Rays (Caustics panel)" },
        { key: "samples", type: "int32", eval: "C.scene.caustic.spp", visible: "web",
          description: "The scene's Samples (Caustics panel)" },
        { key: "blendfile", type: "string", required: true, visible: "web",
          description: "Path of the .blend file to render" },
    ]
};

// The expression each mode runs: its arguments come after `--` (the
// folder or output path, then the chunk's runs of frames as "first-last").
// bpy.ops raises on an operator's error, and --python-exit-code makes
// Blender exit with it, so the task fails with the message in its log.
const OPERATORS = {
    bake: "bpy.ops.caustic.bake_animation(directory=path, frame_start=first, frame_end=last)",
    caustics: "bpy.ops.caustic.render_animation(filepath=path, frame_start=first, frame_end=last)",
};

function setting(settings, key) {
    const value = settings[key];
    if (value !== undefined && value !== null && value !== "") {
        return value;
    }
    const declared = JOB_TYPE.settings.find((s) => s.key == key);
    if (declared.default === undefined) {
        throw `The job has no "${key}" setting: ${declared.description}`;
    }
    return declared.default;
}

function compileJob(job) {
    const settings = job.settings;
    const mode = setting(settings, "mode");
    if (!MODES.includes(mode)) {
        throw `Unknown mode "${mode}": use "bake" or "caustics"`;
    }
    const chunkSize = setting(settings, "chunk_size");
    if (!Number.isInteger(chunkSize) || chunkSize < 1) {
        throw `chunk_size must be a whole number of frames, 1 or more (got ${chunkSize})`;
    }
    const frames = setting(settings, "frames");
    for (const chunk of frameChunker(frames, chunkSize)) {
        job.addTask(chunkTask(settings, mode, chunk));
    }
}

// The chunk's frames ("5-8", "5" or "1,3,5-6") as runs of consecutive frames, [[first, last], ...].
function runsOf(chunk) {
    const frames = [];
    for (const part of chunk.split(",")) {
        const [first, last] = part.split("-").map((frame) => parseInt(frame, 10));
        for (let frame = first; frame <= (last === undefined ? first : last); frame++) {
            frames.push(frame);
        }
    }
    const runs = [];
    for (const frame of frames) {
        const run = runs[runs.length - 1];
        if (run && frame == run[1] + 1) {
            run[1] = frame;
        } else {
            runs.push([frame, frame]);
        }
    }
    return runs;
}

function chunkTask(settings, mode, chunk) {
    const runs = runsOf(chunk);
    const expression = "import bpy, sys; path, *runs = sys.argv[sys.argv.index('--') + 1:]; " +
        "[" + OPERATORS[mode] + " for first, last in (map(int, run.split('-')) for run in runs)]";
    let args = ["--python-exit-code", "1", "--python-expr", expression];
    let path = setting(settings, "render_output_path");
    if (mode == "bake") {
        // Blender runs its arguments in order: the bake, then the render of the same frames.
        args = args.concat(["--render-output", path,
                            "--render-frame", runs.map(([a, b]) => a == b ? `${a}` : `${a}..${b}`).join(",")]);
        path = setting(settings, "bake_folder");
    }
    args = args.concat(["--", path, ...runs.map(([a, b]) => `${a}-${b}`)]);
    const name = runs.map(([a, b]) => a == b ? `${a}` : `${a}-${b}`).join(",");
    const task = author.Task(`${mode}-${name}`, "blender");
    task.addCommand(author.Command("blender-render", {
        exe: "{blender}",
        exeArgs: "{blenderArgs}",
        argsBefore: [],
        blendfile: setting(settings, "blendfile"),
        args: args,
    }, frameCount(chunk)));
    return task;
}
