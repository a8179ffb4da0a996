"""Many films in one run: :func:`run_batch` writes ``OUT_DIR/<name>.timeline.json`` per film.

- Inputs are files, folders (their media files, not recursive) or glob patterns (``**`` recurses);
  :func:`collect_inputs` expands them, sorted and without duplicates.
- Each film runs :func:`autohaptics.pipeline.generate` in a worker: a local process pool of
  ``jobs`` processes (spawn context), or one task per film on an existing Dask distributed
  cluster (``scheduler="tcp://HOST:PORT"``; its workers must see the input files at the same
  paths). The worker returns the timeline and this process writes it, so both paths give the
  same files.
- A film is skipped when its timeline exists and was made from the same source (SHA-256) with
  the same resolved parameters and preset. ``OUT_DIR/batch-manifest.json`` records, per output
  name, the source path, its SHA-256 and the parameters' digest; without an entry the existing
  timeline's ``source.sha256`` and ``generator`` are read instead.
- Output names are the file stem; a stem already taken (another film of the run, or one the
  manifest records for a file that still exists) gets ``-<8 hex of the source path's SHA-1>``.
  A film keeps the name the manifest gave it in earlier runs.
- A failing film does not stop the others: every failure is in the :class:`BatchReport` with a
  one-line reason. A worker process that dies is replaced; a film that was being analysed in two
  dying workers is reported as failed.
- One overall progress callback ``progress(stage, fraction)``: films weighted by file size.
"""

from autohaptics.batch.films import (MANIFEST_NAME, MEDIA_SUFFIXES, BatchReport, FilmResult, collect_inputs,
                                     load_manifest, output_names, params_digest, save_manifest)
from autohaptics.batch.run import run_batch
from autohaptics.batch.work import process_film

__all__ = ["BatchReport", "FilmResult", "MANIFEST_NAME", "MEDIA_SUFFIXES", "collect_inputs", "load_manifest",
           "output_names", "params_digest", "process_film", "run_batch", "save_manifest"]
