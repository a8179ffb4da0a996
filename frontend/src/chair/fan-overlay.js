/**
 * The fan grid (17 x 9 on the chair) drawn over the video picture at the playhead (row 0 = top of the frame,
 * column 0 = left). The canvas covers the element; the grid covers only the picture inside it
 * (object-fit: contain leaves bars).
 */

export class FanOverlay {
  /**
   * @param {HTMLCanvasElement} canvas absolutely placed over the video
   * @param {HTMLVideoElement} video
   * @param {{rows: number, cols: number}} grid the fan grid's size
   */
  constructor(canvas, video, { rows, cols }) {
    this.rows = rows;
    this.cols = cols;
    this.canvas = canvas;
    this.video = video;
    this.ctx = /** @type {CanvasRenderingContext2D} */ (canvas.getContext("2d"));
    /** @type {Float32Array|null} */
    this.grid = null;
    this.visible = false;
    this._ro = new ResizeObserver(() => this.draw());
    this._ro.observe(video);
    video.addEventListener("loadedmetadata", () => this.draw());
  }

  /** @param {boolean} on */
  setVisible(on) {
    this.visible = on;
    this.canvas.hidden = !on;
    this.draw();
  }

  /** @param {Float32Array|null} grid rows x cols fan levels, row-major */
  update(grid) {
    this.grid = grid;
    if (this.visible) this.draw();
  }

  /** The picture's rectangle inside the element (CSS px). */
  pictureRect() {
    const w = this.video.clientWidth;
    const h = this.video.clientHeight;
    const vw = this.video.videoWidth || 16;
    const vh = this.video.videoHeight || 9;
    const s = Math.min(w / vw, h / vh);
    const pw = vw * s;
    const ph = vh * s;
    return { x: (w - pw) / 2, y: (h - ph) / 2, w: pw, h: ph };
  }

  draw() {
    if (!this.visible) return;
    const dpr = window.devicePixelRatio || 1;
    const w = this.video.clientWidth;
    const h = this.video.clientHeight;
    if (this.canvas.width !== Math.round(w * dpr) || this.canvas.height !== Math.round(h * dpr)) {
      this.canvas.width = Math.round(w * dpr);
      this.canvas.height = Math.round(h * dpr);
    }
    const ctx = this.ctx;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, w, h);
    const r = this.pictureRect();
    const { rows, cols } = this;
    const cw = r.w / cols;
    const ch = r.h / rows;
    for (let row = 0; row < rows; row++) {
      for (let col = 0; col < cols; col++) {
        const v = this.grid ? this.grid[row * cols + col] : 0;
        if (v > 0) {
          ctx.fillStyle = `rgba(103, 232, 249, ${0.15 + 0.55 * v})`;
          ctx.fillRect(r.x + col * cw, r.y + row * ch, cw, ch);
        }
      }
    }
    ctx.strokeStyle = "rgba(255, 255, 255, 0.22)";
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let c = 0; c <= cols; c++) {
      const x = Math.round(r.x + c * cw) + 0.5;
      ctx.moveTo(x, r.y);
      ctx.lineTo(x, r.y + r.h);
    }
    for (let row = 0; row <= rows; row++) {
      const y = Math.round(r.y + row * ch) + 0.5;
      ctx.moveTo(r.x, y);
      ctx.lineTo(r.x + r.w, y);
    }
    ctx.stroke();
  }

  destroy() {
    this._ro.disconnect();
  }
}
