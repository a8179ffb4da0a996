"""``run_batch``: many films in one run, locally or on a Dask cluster."""

from __future__ import annotations

import os
from typing import Any, Iterable

from autohaptics.batch.films import (
    OUTPUT_SUFFIX,
    BatchReport,
    collect_inputs,
    load_manifest,
    output_names,
    params_digest,
    recorded_sha,
)
from autohaptics.batch.local import run_local
from autohaptics.batch.work import Film, Run
from autohaptics.errors import ParameterError
from autohaptics.outputs import prepare_folder
from autohaptics.progress import ProgressFn, null_progress


def run_batch(inputs: Iterable[str | os.PathLike], out_dir: str | os.PathLike, params: Any = None,
              preset: str | None = None, *, jobs: int = 1, scheduler: str | None = None,
              progress: ProgressFn | None = None, style: Any = None) -> BatchReport:
    """Generate a timeline per film of ``inputs`` into ``out_dir`` (created when missing).

    inputs : files, folders and glob patterns (:func:`collect_inputs`).
    params, preset : :class:`~autohaptics.params.GenerateParams` and the preset name they were
        resolved from (:func:`~autohaptics.params.resolve_params`); default: the default preset.
    jobs : local worker processes (>= 1); ignored when ``scheduler`` is given.
    scheduler : address of a Dask distributed scheduler (``tcp://HOST:PORT``): one task per film
        on that cluster instead of local processes.
    style : an :class:`autohaptics.style.Style` every timeline is derived in (part of what makes
        an existing timeline up to date).

    Raises ParameterError for usage errors (no films, bad ``jobs``, ``out_dir`` is a file, bad
    scheduler address); film failures are in the report, never raised. Ctrl+C cancels the
    running films (KeyboardInterrupt propagates); films finished so far keep their timelines.
    """
    from autohaptics.params import DEFAULT_PRESET, resolve_params

    preset = preset or DEFAULT_PRESET
    if params is None:
        params, preset = resolve_params(preset)
    if scheduler is None and (not isinstance(jobs, int) or jobs < 1):
        raise ParameterError(f"jobs must be a whole number >= 1, got {jobs!r}")
    if scheduler is not None and not (isinstance(scheduler, str) and "://" in scheduler
                                      and scheduler.split("://", 1)[1]):
        raise ParameterError(f"scheduler must be an address like tcp://HOST:PORT, got {scheduler!r}")
    if scheduler is not None:
        from autohaptics.batch.cluster import check_address

        check_address(scheduler)  # a bad address fails at once, before any film is looked at
    sources = collect_inputs(inputs)
    out = prepare_folder(out_dir, label="output folder")
    manifest = load_manifest(out)
    names = output_names(sources, manifest)
    digest = params_digest(params, preset, style)
    films = []
    for i, src in enumerate(sources):
        output = out / f"{names[src]}{OUTPUT_SUFFIX}"
        try:
            weight = float(max(src.stat().st_size, 1))
        except OSError:
            weight = 1.0
        films.append(Film(i, src, output, names[src], weight,
                           recorded_sha(output, manifest.get(names[src]), src, digest, params, preset, style)))
    run = Run(films, out, manifest, digest, preset, progress or null_progress)
    run.report_progress()
    if scheduler is not None:
        from autohaptics.batch.cluster import run_dask  # dask is imported only for a cluster

        run_dask(run, params, preset, scheduler, style)
    else:
        run_local(run, params, preset, jobs, style)
    return BatchReport(out, [run.results[f.index] for f in films])
