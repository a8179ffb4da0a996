/**
 * HTTP plumbing under the API client: every failure becomes an ApiError carrying the server's
 * one-sentence `detail`, and multipart uploads go through XMLHttpRequest (fetch reports no upload
 * progress).
 */

export class ApiError extends Error {
  /**
   * @param {number} status HTTP status (0 when the request never reached the server)
   * @param {string} detail
   */
  constructor(status, detail) {
    super(detail);
    this.name = "ApiError";
    this.status = status;
    this.detail = detail;
  }
}

/** The one-line text of an error, for the status line and toasts. @param {unknown} err */
export function errorText(err) {
  if (err instanceof ApiError) return err.detail;
  if (err instanceof Error) return err.message;
  return String(err);
}

/**
 * The response of a request, or ApiError when it never arrived or failed.
 * @param {Promise<Response>} pending
 * @param {string} what "METHOD path", for messages
 */
export async function reach(pending, what) {
  let res;
  try {
    res = await pending;
  } catch (err) {
    throw new ApiError(0, `The server could not be reached (${what}).`);
  }
  if (!res.ok) throw await errorFrom(res, what);
  return res;
}

/** JSON text, or null when it is not JSON. @param {string} text */
export function parseJson(text) {
  try {
    return JSON.parse(text);
  } catch (err) {
    return null;
  }
}

/**
 * POST a file (multipart field `file`) and extra form fields, reporting upload progress.
 * @param {string} url
 * @param {string} path the route, for messages
 * @param {File} file
 * @param {Record<string, string>} fields
 * @param {(fraction: number, loaded: number, total: number) => void} onProgress
 * @returns {{promise: Promise<any>, abort: () => void}}
 */
export function postMultipart(url, path, file, fields, onProgress) {
  const xhr = new XMLHttpRequest();
  const form = new FormData();
  for (const [k, v] of Object.entries(fields)) form.append(k, v);
  form.append("file", file, file.name);
  const promise = new Promise((resolve, reject) => {
    xhr.open("POST", url);
    xhr.responseType = "text";
    xhr.setRequestHeader("Accept", "application/json");
    xhr.upload.onprogress = (e) => {
      if (e.lengthComputable && e.total > 0) onProgress(e.loaded / e.total, e.loaded, e.total);
    };
    xhr.upload.onload = () => onProgress(1, file.size, file.size);
    xhr.onload = () => {
      const body = xhr.responseText ? parseJson(xhr.responseText) : null;
      if (xhr.status >= 200 && xhr.status < 300) resolve(body);
      else reject(new ApiError(xhr.status, detailOf(body, xhr.status, `POST ${path}`)));
    };
    xhr.onerror = () => reject(new ApiError(0, `The upload to ${path} failed: the server could not be reached.`));
    xhr.onabort = () => reject(new ApiError(0, "The upload was cancelled."));
    xhr.send(form);
  });
  return { promise, abort: () => xhr.abort() };
}

/**
 * @param {Response} res
 * @param {string} what
 */
async function errorFrom(res, what) {
  let body = null;
  try {
    body = await res.json();
  } catch (err) {
    body = null;
  }
  return new ApiError(res.status, detailOf(body, res.status, what));
}

/**
 * @param {any} body
 * @param {number} status
 * @param {string} what
 */
function detailOf(body, status, what) {
  const d = body && body.detail;
  if (typeof d === "string" && d) return d;
  if (Array.isArray(d) && d.length) {
    // FastAPI validation errors: [{loc, msg, type}]
    return d.map((e) => `${(e.loc || []).slice(1).join(".") || "request"}: ${e.msg}`).join("; ");
  }
  return `${what} failed with HTTP ${status}.`;
}
