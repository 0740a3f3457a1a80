"""Engine jobs run one after another, each between two calls on Blender's
main thread: `prepare(step)` reads the scene (for a frame: sets it first)
and returns the RenderJob, `finish(step, job)` writes its result. A still
render is one step; an animation is a step per frame. No bpy here: the
callers pass in the calls that touch Blender.

In the UI a modal timer calls `tick()`, which never waits on the engine; in
the background `run()` does every step here."""

from __future__ import annotations

from typing import Callable, Sequence

from .job import RenderJob


class StepError(Exception):
    """`prepare` or `finish` could not do its step; the message tells the user why."""


class JobRunner:
    """After the run, `done` lists the steps finished, `error` holds the
    message that stopped it (None if none did), `cancelled` says whether
    a stop request ended it early, and `last` is the last finished job
    (only it is kept: a frame's images are large).

    `parts` says the steps make one result together (Compare's caustic
    render and its Cycles reference): a stop then cancels the step running,
    as it does in a run of one step. A step's job is a RenderJob, or
    anything with its attributes (comparison.cycles.CyclesReference)."""

    def __init__(self, steps: Sequence, prepare: Callable[[object], RenderJob],
                 finish: Callable[[object, RenderJob], None], parts: bool = False):
        self.steps, self._prepare, self._finish = list(steps), prepare, finish
        self._parts = parts or len(self.steps) == 1
        self.done: list = []
        self.last: RenderJob | None = None
        self.error: str | None = None
        self.cancelled = False
        self.job: RenderJob | None = None
        self._stop_requests = 0

    @property
    def fraction(self) -> float:
        current = self.job.fraction if self.job is not None else 0.0
        return min(1.0, (len(self.done) + current) / max(1, len(self.steps)))

    @property
    def step(self):
        """The step running now (or about to)."""
        return self.steps[min(len(self.done), len(self.steps) - 1)]

    @property
    def stage(self) -> str:
        return self.job.stage if self.job is not None else ""

    def stop(self) -> None:
        """Stop after the step running now; a second call (or a run of one
        step, or of parts) stops that step too."""
        self._stop_requests += 1
        if self.job is not None and (self._stop_requests > 1 or self._parts):
            self.job.cancel()

    def _begin(self) -> bool:
        """Prepare the next step; False when there is none to run."""
        if self.cancelled or self.error is not None or len(self.done) == len(self.steps):
            return False
        if self._stop_requests:
            self.cancelled = True
            return False
        try:
            self.job = self._prepare(self.steps[len(self.done)])
        except StepError as exc:
            self.error = str(exc)
            return False
        return True

    def _end(self) -> None:
        job, self.job = self.job, None
        if job.cancelled:
            self.cancelled = True
        elif job.error is not None:
            self.error = job.error
        else:
            try:
                self._finish(self.steps[len(self.done)], job)
            except StepError as exc:
                self.error = str(exc)
                return
            self.done.append(self.steps[len(self.done)])
            self.last = job

    def run(self) -> None:
        """Every step, here and now."""
        while self._begin():
            self.job.run()
            self._end()

    def tick(self) -> bool:
        """Advance without waiting: end a finished job, start the next. False once all is done."""
        if self.job is not None:
            if self.job.running:
                return True
            self._end()
        if not self._begin():
            return False
        self.job.start()
        return True

    def abort(self) -> None:
        """Blender is taking the operator away: cancel the running job and wait for it."""
        if self.job is not None:
            self.job.cancel()
            self.job.wait()
            self.job = None
        self.cancelled = True
