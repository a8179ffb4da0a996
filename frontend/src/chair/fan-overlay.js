/**
 * The fan grid (17 x 9 on the chair) drawn over the video picture at the playhead (row 0 = top of the picture,
 * column 0 = left). The canvas covers the element; the grid covers only the part of the picture the analysis
 * read (the timeline's `picture` box: the active picture inside the film's own black bars, a 3D film's first
 * view; the whole picture where it says nothing), inside the bars object-fit: contain leaves.
 *
 * It also picks a region of fans for the range operations: a drag selects a rectangle of cells,
 * Ctrl (Cmd) + drag paints cells as a brush and adds them, a click outside the picture or Escape
 * clears the region (outlined in yellow).
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
    /** @type {{x: number, y: number, w: number, h: number}|null} the grid's part of the frame, 0..1 */
    this.box = null;
    this.visible = false;
    /** @type {Set<number>} the picked cells, row * cols + col */
    this.region = new Set();
    /** @type {(cells: Array<[number, number]>) => void} told whenever the region changes */
    this.onRegion = () => {};
    /** @type {{anchor: number, brush: boolean, base: Set<number>}|null} */
    this._drag = null;
    this._ro = new ResizeObserver(() => this.draw());
    this._ro.observe(video);
    video.addEventListener("loadedmetadata", () => this.draw());
    canvas.addEventListener("pointerdown", (e) => this._down(e));
    canvas.addEventListener("pointermove", (e) => this._move(e));
    canvas.addEventListener("pointerup", () => (this._drag = null));
    canvas.addEventListener("keydown", (e) => {
      if (e.key === "Escape" && this.region.size) this.setRegion([]);
    });
  }

  /** The picked cells as [row, col] pairs, row-major. @returns {Array<[number, number]>} */
  cells() {
    return [...this.region].sort((a, b) => a - b).map((i) => /** @type {[number, number]} */ ([Math.floor(i / this.cols), i % this.cols]));
  }

  /** @param {Array<[number, number]>} cells */
  setRegion(cells) {
    this.region = new Set(cells.map(([r, c]) => r * this.cols + c));
    this.onRegion(this.cells());
    this.draw();
  }

  /** The cell under a pointer event, -1 outside the picture. @param {PointerEvent} e */
  cellAt(e) {
    const box = this.canvas.getBoundingClientRect();
    const r = this.pictureRect();
    const col = Math.floor(((e.clientX - box.x - r.x) / r.w) * this.cols);
    const row = Math.floor(((e.clientY - box.y - r.y) / r.h) * this.rows);
    return row >= 0 && row < this.rows && col >= 0 && col < this.cols ? row * this.cols + col : -1;
  }

  /** @param {PointerEvent} e */
  _down(e) {
    const cell = this.cellAt(e);
    this.canvas.focus();
    if (cell < 0) {
      this.setRegion([]);
      return;
    }
    this.canvas.setPointerCapture(e.pointerId);
    const brush = e.ctrlKey || e.metaKey;
    this._drag = { anchor: cell, brush, base: brush ? new Set(this.region) : new Set() };
    this._move(e);
  }

  /** @param {PointerEvent} e */
  _move(e) {
    const d = this._drag;
    const cell = d ? this.cellAt(e) : -1;
    if (!d || cell < 0) return;
    if (d.brush) {
      d.base.add(cell);
      this.region = new Set(d.base);
    } else {
      const cols = this.cols;
      const [r0, r1] = [Math.floor(d.anchor / cols), Math.floor(cell / cols)].sort((a, b) => a - b);
      const [c0, c1] = [d.anchor % cols, cell % cols].sort((a, b) => a - b);
      this.region = new Set();
      for (let r = r0; r <= r1; r++) for (let c = c0; c <= c1; c++) this.region.add(r * cols + c);
    }
    this.onRegion(this.cells());
    this.draw();
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

  /**
   * The part of the frame the grid covers, fractions 0..1 (null or a box outside 0..1: all of it).
   * @param {{x: number, y: number, w: number, h: number}|null|undefined} box
   */
  setBox(box) {
    const ok = box && [box.x, box.y, box.w, box.h].every(Number.isFinite) && box.w > 0 && box.h > 0 &&
      box.x >= 0 && box.y >= 0 && box.x + box.w <= 1.000001 && box.y + box.h <= 1.000001;
    this.box = ok ? { x: box.x, y: box.y, w: box.w, h: box.h } : null;
    if (this.visible) this.draw();
  }

  /** The grid's rectangle inside the element (CSS px): the picture's, or the part of it the box names. */
  pictureRect() {
    const w = this.video.clientWidth;
    const h = this.video.clientHeight;
    const vw = this.video.videoWidth || 16;
    const vh = this.video.videoHeight || 9;
    const s = Math.min(w / vw, h / vh);
    const pw = vw * s;
    const ph = vh * s;
    const b = this.box || { x: 0, y: 0, w: 1, h: 1 };
    return { x: (w - pw) / 2 + b.x * pw, y: (h - ph) / 2 + b.y * ph, w: b.w * pw, h: b.h * ph };
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
    ctx.strokeStyle = "#facc15";
    ctx.lineWidth = 2;
    for (const i of this.region) ctx.strokeRect(r.x + (i % cols) * cw + 1, r.y + Math.floor(i / cols) * ch + 1, cw - 2, ch - 2);
  }

  destroy() {
    this._ro.disconnect();
  }
}
