"""A background Job driven by a modal operator: the one skeleton of the bakes (operators.py) and
the Variations grid (variations.py).

The operator (which has a `synchronous` property) calls run_job() from execute(). In the
background, without a window, or when asked to be synchronous, the job runs in the calling thread
and job_finished() gives the result at once.
Otherwise the job is held (jobs.active_jobs counts it), a timer and a modal handler are added,
and the worker thread starts at the first timer tick; each tick then calls job_ticked(); Esc
cancels; when the worker is done, job_finished() runs on the main thread.

Why the worker starts at the first tick, not in execute(): an operator may run inside another
one (Apply Variation starts the next grid), and Blender ends that outer operator with an undo
push. A worker thread started before that push crashed Blender 3.4.1 (a segmentation fault in
the worker's Python, every run of tests/blender/preview_test.py); started from the event loop,
after the operators have returned, it never did.
"""

from __future__ import annotations

import bpy

from . import jobs


class ModalJob:
    """Mixed into a bpy.types.Operator. Override the job_* hooks that apply."""

    timer_step = 0.1  # seconds between ticks

    _job = None
    _timer = None

    # hooks ------------------------------------------------------------------------------
    def job_started(self, context) -> None:
        """After the modal handler is added (the worker starts at the first tick)."""

    def job_ticked(self, context) -> None:
        """Each timer tick and after Esc, while the job runs."""

    def job_ended(self, context) -> None:
        """The timer removed: the job finished, or the operator was closed."""

    def job_finished(self, context) -> set:
        """The job done, failed or cancelled: the operator's result. Main thread."""
        return {"FINISHED"} if self._job.state == jobs.Job.DONE else {"CANCELLED"}

    def job_closed(self, context) -> None:
        """Blender closed the operator (the file closed, Blender quit) and the job was stopped."""

    def job_superseded(self) -> bool:
        """Whether newer work replaced this job (it is then cancelled and the operator ends)."""
        return False

    # the skeleton -----------------------------------------------------------------------
    def run_job(self, context, job: jobs.Job) -> set:
        self._job = job
        if self.synchronous or bpy.app.background or context.window is None:
            job.run()
            return self.job_finished(context)
        job.hold()
        wm = context.window_manager
        self._timer = wm.event_timer_add(self.timer_step, window=context.window)
        wm.modal_handler_add(self)
        self.job_started(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        job = self._job
        if self.job_superseded():
            job.cancel()
            self._end(context)
            return {"CANCELLED"}
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()
            self.job_ticked(context)
            return {"RUNNING_MODAL"}
        if event.type == "TIMER":
            job.start()  # at the first tick; a no-op after, or once cancelled
            self.job_ticked(context)
            if job.finished_running:
                job.join()
                self._end(context)
                return self.job_finished(context)
        return {"PASS_THROUGH"}

    def cancel(self, context):
        if self._job is not None:
            self._job.cancel()
            self._job.join()
        self._end(context)
        self.job_closed(context)

    def _end(self, context) -> None:
        if self._timer is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        self.job_ended(context)
