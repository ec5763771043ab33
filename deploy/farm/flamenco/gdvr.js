// Flamenco 3 job type for gdvr: copy into the Manager's scripts/ folder
// (beside flamenco-manager) and restart it; "gdvr" then appears as a job type.
// One render task per chunk of frames, one finalize-tiles task per chunk of
// tiles of the T-GPT window solve (each depends on every render task), then
// one finalize task that depends on all tile tasks and assembles the frames
// (previews, video). Tiles: `gdvr-farm tiles JOB.json --tiles-per-task 100000`.
//
// Workers run the commands through the "exec" command, so gdvr-farm must be
// on their PATH (or set gdvr_farm), and the job file, scene and farm_dir on
// storage every worker sees under the same path (or use Flamenco's
// two-way variables for per-platform paths).
//
// Tasks are idempotent: a requeued or failed-and-retried task renders only
// the frames of its chunk whose buffers are not complete yet.

// "misc" runs on every stock Worker. To send gdvr tasks only to machines that
// have gdvr installed, change it to "gdvr" and add "gdvr" to task_types in
// those Workers' flamenco-worker.yaml.
const TASK_TYPE = "misc";

const JOB_TYPE = {
  label: "gdvr",
  description: "Temporal gradient-domain video render with gdvr-farm",
  settings: [
    { key: "job_file", type: "string", subtype: "file_path", required: true,
      description: "The gdvr job file (JSON) on shared storage" },
    { key: "frames", type: "string", required: true, default: "0-47",
      description: "The job's frames, as in the job file (\"1-100\", \"1,5,10-20\")" },
    { key: "chunk_size", type: "int32", default: 8, propargs: { min: 1 },
      description: "Frames per render task" },
    { key: "farm_dir", type: "string", subtype: "dir_path", required: true,
      description: "Shared folder: buffers/ (per-frame sample buffers) and output/ (final frames, previews, video)" },
    { key: "tiles", type: "string", default: "0",
      description: "Tile indices of the window solve, e.g. 0-11 (gdvr-farm tiles JOB.json)" },
    { key: "tiles_per_task", type: "int32", default: 4, propargs: { min: 1 },
      description: "Tiles per finalize-tiles task" },
    { key: "threads", type: "int32", default: 0, propargs: { min: 0 },
      description: "Render threads per task; 0 = all cores" },
    { key: "gdvr_farm", type: "string", default: "gdvr-farm", visible: "submission",
      description: "The gdvr-farm executable on the Workers" },
  ],
};

function compileJob(job) {
  const settings = job.settings;
  const buffers = settings.farm_dir + "/buffers";
  const output = settings.farm_dir + "/output";

  const renderTasks = [];
  for (const chunk of frameChunker(settings.frames, settings.chunk_size)) {
    const task = author.Task(`render-${chunk}`, TASK_TYPE);
    const args = ["render", settings.job_file, "--frames", chunk, "--buffers", buffers];
    if (settings.threads > 0) args.push("--threads", String(settings.threads));
    task.addCommand(author.Command("exec", { exe: settings.gdvr_farm, args: args }));
    job.addTask(task);
    renderTasks.push(task);
  }

  const tileTasks = [];
  for (const tiles of frameChunker(settings.tiles, settings.tiles_per_task)) {
    const task = author.Task(`finalize-tiles-${tiles}`, TASK_TYPE);
    task.addCommand(author.Command("exec", {
      exe: settings.gdvr_farm,
      args: ["finalize", settings.job_file, "--tiles", tiles, "--buffers", buffers, "--out", output],
    }));
    for (const render of renderTasks) task.addDependency(render);
    job.addTask(task);
    tileTasks.push(task);
  }

  const finalize = author.Task("finalize", TASK_TYPE);
  finalize.addCommand(author.Command("exec", {
    exe: settings.gdvr_farm,
    args: ["finalize", settings.job_file, "--buffers", buffers, "--out", output, "--video"],
  }));
  for (const task of tileTasks) finalize.addDependency(task);
  job.addTask(finalize);
}
