// microfrep studio: a small WebGL viewer for the studio's meshes.
// Orbit (left drag), pan (right drag or shift + left drag), zoom (wheel),
// reset (double click). The view refits when an edit changes the model's
// box materially (camera.js). A section plane and a cut-away octant are clipped
// in the fragment shader; the mesh is closed, so where the clip opens it
// the inside faces show, drawn in a flat cap colour: a capped cut. The
// value map of the section plane (a server-rendered image) can be laid
// on the plane. Vertices carry attribute values for colouring.
"use strict";

(function () {
  const Cam = window.StudioCamera;
  // --- 4x4 matrices, column-major as WebGL takes them ---
  function perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1,
      0, 0, 2 * far * near * nf, 0]);
  }
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function norm(a) { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }
  function lookAt(eye, at, up) {
    const z = norm(sub(eye, at)), x = norm(cross(up, z)), y = cross(z, x);
    return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
      -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
  }
  function mul(a, b) {
    const o = new Float32Array(16);
    for (let c = 0; c < 4; c++)
      for (let r = 0; r < 4; r++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
        o[c * 4 + r] = s;
      }
    return o;
  }

  const VS = `
attribute vec3 aPos; attribute vec3 aNrm; attribute float aAttr;
uniform mat4 uMVP;
varying vec3 vPos; varying vec3 vNrm; varying float vAttr;
void main() { vPos = aPos; vNrm = aNrm; vAttr = aAttr; gl_Position = uMVP * vec4(aPos, 1.0); }`;

  const FS = `
precision highp float;
varying vec3 vPos; varying vec3 vNrm; varying float vAttr;
uniform vec4 uClip; uniform float uClipOn;
uniform vec3 uCutC; uniform vec3 uCutS; uniform float uCutOn;
uniform vec3 uEye; uniform float uAttrOn; uniform vec2 uAttrRange;
uniform vec3 uBase; uniform vec3 uCap;
vec3 cmap(float t) {
  // A perceptual blue-green-yellow ramp (after viridis), by pieces.
  vec3 a = vec3(0.267, 0.005, 0.329), b = vec3(0.128, 0.567, 0.551), c = vec3(0.993, 0.906, 0.144);
  return t < 0.5 ? mix(a, b, t * 2.0) : mix(b, c, t * 2.0 - 1.0);
}
void main() {
  if (uClipOn > 0.5 && dot(uClip.xyz, vPos) + uClip.w > 0.0) discard;
  if (uCutOn > 0.5) {
    vec3 d = (vPos - uCutC) * uCutS;
    if (d.x > 0.0 && d.y > 0.0 && d.z > 0.0) discard;
  }
  if (!gl_FrontFacing) { gl_FragColor = vec4(uCap, 1.0); return; }
  vec3 base = uBase;
  if (uAttrOn > 0.5) {
    float w = max(uAttrRange.y - uAttrRange.x, 1e-20);
    base = cmap(clamp((vAttr - uAttrRange.x) / w, 0.0, 1.0));
  }
  vec3 n = normalize(vNrm);
  vec3 v = normalize(uEye - vPos);
  vec3 l1 = normalize(v + vec3(0.0, 0.0, 0.6));
  float d1 = max(dot(n, l1), 0.0), d2 = max(dot(n, v), 0.0);
  float spec = pow(max(dot(n, normalize(l1 + v)), 0.0), 48.0);
  vec3 col = base * (0.22 + 0.55 * d1 + 0.28 * d2) + vec3(0.18) * spec;
  gl_FragColor = vec4(col, 1.0);
}`;

  const QVS = `
attribute vec3 aPos; attribute vec2 aUV; uniform mat4 uMVP; varying vec2 vUV;
void main() { vUV = aUV; gl_Position = uMVP * vec4(aPos, 1.0); }`;
  const QFS = `
precision mediump float; varying vec2 vUV; uniform sampler2D uTex;
void main() {
  vec4 c = texture2D(uTex, vUV);
  // Inside (red, white at zero) and the black contour opaque; outside (blue) faint.
  float inside = c.r >= c.b - 0.004 ? 1.0 : 0.0;
  gl_FragColor = vec4(c.rgb, mix(0.35, 0.95, inside));
}`;

  function compile(gl, vs, fs) {
    const mk = (type, src) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      return s;
    };
    const p = gl.createProgram();
    gl.attachShader(p, mk(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, mk(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    const u = {}, a = {};
    const nu = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < nu; i++) { const n = gl.getActiveUniform(p, i).name; u[n] = gl.getUniformLocation(p, n); }
    const na = gl.getProgramParameter(p, gl.ACTIVE_ATTRIBUTES);
    for (let i = 0; i < na; i++) { const n = gl.getActiveAttrib(p, i).name; a[n] = gl.getAttribLocation(p, n); }
    return { p, u, a };
  }

  // Parses a mesh blob (see the crate's wire module).
  function parseMesh(buf) {
    const magic = new TextDecoder().decode(new Uint8Array(buf, 0, 8));
    if (magic !== "MFMESH01") throw new Error("not a mesh blob");
    const h = new Uint32Array(buf, 8, 4);
    const n = h[0], t = h[1], k = h[2];
    let at = 24;
    const pos = new Float32Array(buf, at, 3 * n); at += 12 * n;
    const nrm = new Float32Array(buf, at, 3 * n); at += 12 * n;
    const attrs = [];
    for (let i = 0; i < k; i++) { attrs.push(new Float32Array(buf, at, n)); at += 4 * n; }
    const idx = new Uint32Array(buf, at, 3 * t);
    return { n, t, pos, nrm, attrs, idx };
  }

  // Replaces zero normals (where the gradient vanished) by face normals.
  function fixNormals(m) {
    let bad = 0;
    for (let i = 0; i < m.n; i++) {
      const l = Math.hypot(m.nrm[3 * i], m.nrm[3 * i + 1], m.nrm[3 * i + 2]);
      if (!(l > 0.5)) bad++;
    }
    if (!bad) return m.nrm;
    const acc = new Float32Array(m.nrm.length);
    const p = m.pos;
    for (let f = 0; f < m.t; f++) {
      const a = m.idx[3 * f], b = m.idx[3 * f + 1], c = m.idx[3 * f + 2];
      const e1 = [p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1], p[3 * b + 2] - p[3 * a + 2]];
      const e2 = [p[3 * c] - p[3 * a], p[3 * c + 1] - p[3 * a + 1], p[3 * c + 2] - p[3 * a + 2]];
      const nn = cross(e1, e2);
      for (const v of [a, b, c]) for (let j = 0; j < 3; j++) acc[3 * v + j] += nn[j];
    }
    const out = new Float32Array(m.nrm);
    for (let i = 0; i < m.n; i++) {
      const l = Math.hypot(out[3 * i], out[3 * i + 1], out[3 * i + 2]);
      if (!(l > 0.5)) {
        const q = norm([acc[3 * i], acc[3 * i + 1], acc[3 * i + 2]]);
        out[3 * i] = q[0]; out[3 * i + 1] = q[1]; out[3 * i + 2] = q[2];
      }
    }
    return out;
  }

  class Viewer {
    constructor(canvas) {
      this.canvas = canvas;
      const opts = { antialias: true, preserveDrawingBuffer: true, alpha: false };
      let gl = canvas.getContext("webgl2", opts);
      this.webgl2 = !!gl;
      if (!gl) {
        gl = canvas.getContext("webgl", opts) || canvas.getContext("experimental-webgl", opts);
        if (gl && !gl.getExtension("OES_element_index_uint")) gl = null;
      }
      this.gl = gl;
      this.ok = !!gl;
      this.mesh = null;
      this.bounds = [[-1, -1, -1], [1, 1, 1]];
      this.yaw = -0.785; this.pitch = 0.6; this.dist = 4; this.target = [0, 0, 0];
      // The box the view was last fitted to, how often it was, and why.
      this.fitted = null;
      this.refits = 0;
      this.lastRefit = null;
      this.section = { axis: -1, value: 0, flip: false };
      this.cutaway = false;
      this.attr = -1;
      this.attrRange = [0, 1];
      this.quad = null;
      this.dirty = true;
      if (!this.ok) return;
      try {
        this.prog = compile(gl, VS, FS);
        this.qprog = compile(gl, QVS, QFS);
      } catch (e) {
        console.error(e);
        this.ok = false;
        return;
      }
      this.buf = { pos: gl.createBuffer(), nrm: gl.createBuffer(), attr: gl.createBuffer(), idx: gl.createBuffer() };
      this.qbuf = gl.createBuffer();
      this.tex = gl.createTexture();
      this.hookInput();
      const loop = () => {
        if (this.dirty) { this.dirty = false; this.draw(); }
        requestAnimationFrame(loop);
      };
      requestAnimationFrame(loop);
      window.addEventListener("resize", () => { this.dirty = true; });
    }

    hookInput() {
      const c = this.canvas;
      let drag = null;
      c.addEventListener("contextmenu", (e) => e.preventDefault());
      c.addEventListener("mousedown", (e) => {
        drag = { x: e.clientX, y: e.clientY, mode: e.button === 2 || e.shiftKey ? "pan" : e.ctrlKey || e.altKey ? "section" : "orbit" };
        e.preventDefault();
      });
      window.addEventListener("mouseup", () => { drag = null; });
      window.addEventListener("mousemove", (e) => {
        if (!drag) return;
        const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
        drag.x = e.clientX; drag.y = e.clientY;
        if (drag.mode === "orbit") {
          this.yaw -= dx * 0.008;
          this.pitch = Math.max(-1.55, Math.min(1.55, this.pitch + dy * 0.008));
        } else if (drag.mode === "pan") {
          const { right, up } = this.axes();
          const s = this.dist * 0.0015;
          for (let a = 0; a < 3; a++) this.target[a] += (-dx * right[a] + dy * up[a]) * s;
        } else if (drag.mode === "section" && this.section.axis >= 0) {
          const a = this.section.axis, b = this.bounds;
          const span = b[1][a] - b[0][a];
          this.setSection(a, Math.max(b[0][a], Math.min(b[1][a], this.section.value - dy * span / 300)), this.section.flip);
          if (this.onSectionDrag) this.onSectionDrag(this.section.value);
        }
        this.dirty = true;
      });
      c.addEventListener("wheel", (e) => {
        e.preventDefault();
        this.dist *= Math.exp(e.deltaY * 0.0012);
        this.dirty = true;
      }, { passive: false });
      c.addEventListener("dblclick", () => this.resetView());
    }

    axes() { return Cam.axes(this.yaw, this.pitch); }

    eye() { return Cam.eye(this.camera()); }

    camera() {
      return { yaw: this.yaw, pitch: this.pitch, dist: this.dist, target: this.target.slice(), fov: this.fov() };
    }

    aspect() {
      const c = this.canvas;
      return c.clientWidth > 0 && c.clientHeight > 0 ? c.clientWidth / c.clientHeight : 1;
    }

    // The model's new box. With `reset` the view is fitted afresh (iso);
    // otherwise it is refitted, keeping the orbit angles, when the box
    // differs materially from the one the view was fitted to (see
    // camera.js: more than 25 % in size or position, or off screen).
    setBounds(b, reset) {
      this.bounds = b;
      if (reset) this.resetView();
      else {
        const why = Cam.refitReason(this.fitted, b, this.camera(), this.aspect());
        if (why) this.refit(why);
      }
      this.dirty = true;
    }

    // Fits target and distance to the box, keeping yaw and pitch.
    refit(why) {
      const c = Cam.fit(this.bounds, this.yaw, this.pitch, this.fov());
      this.target = c.target;
      this.dist = c.dist;
      this.fitted = this.bounds;
      this.refits++;
      this.lastRefit = why || "refit";
      this.dirty = true;
    }

    resetView(view) {
      const v = view || "iso";
      const presets = { iso: [-0.785, 0.6], front: [-Math.PI / 2, 0], top: [-Math.PI / 2, 1.5499], side: [0, 0] };
      [this.yaw, this.pitch] = presets[v] || presets.iso;
      this.refit("reset");
    }

    fov() { return Cam.FOV; }

    // A mesh blob (ArrayBuffer); keeps the view.
    setMesh(buf) {
      if (!this.ok) return;
      const gl = this.gl;
      const m = parseMesh(buf);
      const nrm = fixNormals(m);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.buf.pos);
      gl.bufferData(gl.ARRAY_BUFFER, m.pos, gl.STATIC_DRAW);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.buf.nrm);
      gl.bufferData(gl.ARRAY_BUFFER, nrm, gl.STATIC_DRAW);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.buf.idx);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, m.idx, gl.STATIC_DRAW);
      this.mesh = { n: m.n, t: m.t, attrs: m.attrs };
      this.uploadAttr();
      this.dirty = true;
    }

    // Colour by attribute k (-1: plain), over [lo, hi].
    setAttribute(k, range) {
      this.attr = k;
      if (range) this.attrRange = range;
      this.uploadAttr();
      this.dirty = true;
    }

    uploadAttr() {
      if (!this.mesh) return;
      const gl = this.gl;
      const a = this.mesh.attrs[this.attr];
      gl.bindBuffer(gl.ARRAY_BUFFER, this.buf.attr);
      gl.bufferData(gl.ARRAY_BUFFER, a || new Float32Array(this.mesh.n), gl.STATIC_DRAW);
    }

    setSection(axis, value, flip) {
      this.section = { axis, value, flip: !!flip };
      this.dirty = true;
    }

    setCutaway(on) { this.cutaway = !!on; this.dirty = true; }

    // The value map of the section plane: an image covering the box's
    // rectangle on the plane (null to hide).
    setSectionImage(img, axis, value) {
      if (!this.ok) return;
      if (!img) { this.quad = null; this.dirty = true; return; }
      const gl = this.gl;
      gl.bindTexture(gl.TEXTURE_2D, this.tex);
      gl.pixelStorei(gl.UNPACK_FLIP_Y_WEBGL, false);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, img);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
      const b = this.bounds;
      const [ra, ua] = axis === 0 ? [1, 2] : axis === 1 ? [0, 2] : [0, 1];
      const corner = (u, v) => {
        const p = [0, 0, 0];
        p[axis] = value;
        p[ra] = b[0][ra] + u * (b[1][ra] - b[0][ra]);
        p[ua] = b[0][ua] + v * (b[1][ua] - b[0][ua]);
        // Image row 0 is the top (largest 'up' coordinate).
        return [...p, u, 1 - v];
      };
      const q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 0), corner(1, 1), corner(0, 1)].flat();
      gl.bindBuffer(gl.ARRAY_BUFFER, this.qbuf);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(q), gl.STATIC_DRAW);
      this.quad = { axis, value };
      this.dirty = true;
    }

    draw() {
      const gl = this.gl, c = this.canvas;
      const w = Math.max(1, Math.round(c.clientWidth * (window.devicePixelRatio || 1)));
      const h = Math.max(1, Math.round(c.clientHeight * (window.devicePixelRatio || 1)));
      if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
      gl.viewport(0, 0, w, h);
      gl.clearColor(0.965, 0.968, 0.975, 1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      gl.enable(gl.DEPTH_TEST);
      if (!this.mesh || !this.mesh.t) return;
      const eye = this.eye();
      const b = this.bounds;
      const r = Math.hypot(b[1][0] - b[0][0], b[1][1] - b[0][1], b[1][2] - b[0][2]);
      const near = Math.max(this.dist - 2 * r, this.dist * 0.01), far = this.dist + 2 * r;
      const mvp = mul(perspective(this.fov(), w / h, near, far), lookAt(eye, this.target, [0, 0, 1]));
      const P = this.prog;
      gl.useProgram(P.p);
      gl.uniformMatrix4fv(P.u.uMVP, false, mvp);
      gl.uniform3fv(P.u.uEye, eye);
      const s = this.section;
      if (s.axis >= 0) {
        const n = [0, 0, 0];
        n[s.axis] = s.flip ? -1 : 1;
        gl.uniform4f(P.u.uClip, n[0], n[1], n[2], s.flip ? s.value : -s.value);
      }
      gl.uniform1f(P.u.uClipOn, s.axis >= 0 ? 1 : 0);
      const ctr = [0, 1, 2].map((a) => 0.5 * (b[0][a] + b[1][a]));
      // The octant nearest the viewer is cut away.
      gl.uniform3fv(P.u.uCutC, ctr);
      gl.uniform3fv(P.u.uCutS, [0, 1, 2].map((a) => (eye[a] >= ctr[a] ? 1 : -1)));
      gl.uniform1f(P.u.uCutOn, this.cutaway ? 1 : 0);
      const on = this.attr >= 0 && this.mesh.attrs[this.attr];
      gl.uniform1f(P.u.uAttrOn, on ? 1 : 0);
      gl.uniform2fv(P.u.uAttrRange, this.attrRange);
      gl.uniform3fv(P.u.uBase, [0.82, 0.6, 0.36]);
      gl.uniform3fv(P.u.uCap, [0.72, 0.22, 0.2]);
      const bind = (buf, loc, size) => {
        if (loc === undefined || loc < 0) return;
        gl.bindBuffer(gl.ARRAY_BUFFER, buf);
        gl.enableVertexAttribArray(loc);
        gl.vertexAttribPointer(loc, size, gl.FLOAT, false, 0, 0);
      };
      bind(this.buf.pos, P.a.aPos, 3);
      bind(this.buf.nrm, P.a.aNrm, 3);
      bind(this.buf.attr, P.a.aAttr, 1);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.buf.idx);
      gl.disable(gl.CULL_FACE);
      gl.drawElements(gl.TRIANGLES, 3 * this.mesh.t, gl.UNSIGNED_INT, 0);
      for (const loc of [P.a.aPos, P.a.aNrm, P.a.aAttr]) if (loc !== undefined && loc >= 0) gl.disableVertexAttribArray(loc);
      if (this.quad && s.axis === this.quad.axis && Math.abs(s.value - this.quad.value) < 1e-12) {
        const Q = this.qprog;
        gl.useProgram(Q.p);
        gl.uniformMatrix4fv(Q.u.uMVP, false, mvp);
        gl.activeTexture(gl.TEXTURE0);
        gl.bindTexture(gl.TEXTURE_2D, this.tex);
        gl.uniform1i(Q.u.uTex, 0);
        gl.bindBuffer(gl.ARRAY_BUFFER, this.qbuf);
        gl.enableVertexAttribArray(Q.a.aPos);
        gl.vertexAttribPointer(Q.a.aPos, 3, gl.FLOAT, false, 20, 0);
        gl.enableVertexAttribArray(Q.a.aUV);
        gl.vertexAttribPointer(Q.a.aUV, 2, gl.FLOAT, false, 20, 12);
        gl.enable(gl.BLEND);
        gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
        gl.depthMask(false);
        gl.drawArrays(gl.TRIANGLES, 0, 6);
        gl.depthMask(true);
        gl.disable(gl.BLEND);
        gl.disableVertexAttribArray(Q.a.aPos);
        gl.disableVertexAttribArray(Q.a.aUV);
      }
    }

    // A hash of the drawn pixels (FNV-1a over RGBA), to tell images apart.
    pixelHash() {
      if (!this.ok) return "none";
      this.draw();
      const gl = this.gl, w = this.canvas.width, h = this.canvas.height;
      const px = new Uint8Array(4 * w * h);
      gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
      let hsh = 0x811c9dc5, lit = 0;
      for (let i = 0; i < px.length; i++) {
        hsh ^= px[i];
        hsh = Math.imul(hsh, 0x01000193) >>> 0;
      }
      for (let i = 0; i < px.length; i += 4) if (px[i] < 240 || px[i + 2] < 240) lit++;
      return { hash: hsh.toString(16), lit, pixels: w * h };
    }
  }

  window.StudioViewer = Viewer;
  window.StudioViewer.parseMesh = parseMesh;
})();
