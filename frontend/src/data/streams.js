/**
 * The server's Server-Sent Event streams: a job's progress until it ends, and the chair's status.
 * EventSource reconnects by itself; a job that ended while the stream was down is asked for.
 */

import { ApiError, parseJson } from "./http.js";

const TERMINAL = new Set(["done", "failed", "cancelled"]);

/** A job in this status will not change any more. @param {string} status */
export function isTerminal(status) {
  return TERMINAL.has(status);
}

/**
 * Follow a job's events until it ends.
 * @param {string} url the job's /events route
 * @param {string} jobId
 * @param {() => Promise<import("./api.js").Job>} askJob reads the job (when the stream drops)
 * @param {(progress: number, stage: string) => void} onProgress
 * @returns {{promise: Promise<import("./api.js").Job>, close: () => void}} resolves with the final job (done, failed or cancelled)
 */
export function watchJob(url, jobId, askJob, onProgress) {
  const source = new EventSource(url);
  let settled = false;
  /** @type {(job: import("./api.js").Job) => void} */
  let resolveFn = () => {};
  /** @type {(err: Error) => void} */
  let rejectFn = () => {};
  const promise = new Promise((resolve, reject) => {
    resolveFn = resolve;
    rejectFn = reject;
  });
  /** @param {import("./api.js").Job} job */
  const finish = (job) => {
    if (settled) return;
    settled = true;
    source.close();
    resolveFn(job);
  };
  source.addEventListener("progress", (e) => {
    const data = parseJson(/** @type {MessageEvent} */ (e).data);
    if (data && typeof data.progress === "number") onProgress(data.progress, String(data.stage || ""));
  });
  for (const name of TERMINAL) {
    source.addEventListener(name, (e) => {
      const data = parseJson(/** @type {MessageEvent} */ (e).data) || {};
      finish({ id: jobId, project_id: data.project_id || "", progress: data.progress ?? 1, ...data, status: name });
    });
  }
  // The stream closes after the final event; a drop before it is retried by EventSource. Ask the
  // job itself so a job that ended while we were disconnected is not waited on forever.
  source.onerror = () => {
    if (settled) return;
    askJob().then(
      (job) => {
        if (isTerminal(job.status)) finish(job);
      },
      (err) => {
        if (settled) return;
        if (err instanceof ApiError && err.status === 404) {
          settled = true;
          source.close();
          rejectFn(err);
        }
      },
    );
  };
  return {
    promise,
    close: () => {
      settled = true;
      source.close();
    },
  };
}

/**
 * Follow the chair's `status` events.
 * @param {string} url the /api/chair/events route
 * @param {(status: import("./api.js").ChairStatus) => void} onStatus
 * @param {(connected: boolean) => void} onStream the stream opened (true) or dropped (false)
 * @returns {() => void} closes the stream
 */
export function watchChair(url, onStatus, onStream) {
  const source = new EventSource(url);
  source.addEventListener("status", (e) => {
    const data = parseJson(/** @type {MessageEvent} */ (e).data);
    if (data) onStatus(data);
  });
  source.onopen = () => onStream(true);
  source.onerror = () => onStream(false);
  return () => source.close();
}
