"""Running the pipeline's heavy work in other processes: one pool of warmed worker processes with
progress and cancellation (:mod:`.pool`), what each worker does first and how it reports
(:mod:`.worker`), and the process's memory housekeeping (:mod:`.heap`). The server's jobs and
``autohaptics batch`` both use it."""

from autohaptics.lazy import lazy_attributes

# Imported when first used: the CLI's heap housekeeping (.heap) needs no multiprocessing machinery.
__getattr__ = lazy_attributes(__name__, {"WorkerPool": "pool", **dict.fromkeys(
    ("PROGRESS_STEP", "Reporter", "init_worker", "queue_sender", "start_worker", "warm_up"), "worker")})

__all__ = ["PROGRESS_STEP", "Reporter", "WorkerPool", "init_worker", "queue_sender", "start_worker", "warm_up"]
