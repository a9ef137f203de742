// microfrep studio: the camera's framing as pure functions (no DOM, no
// WebGL), so that the rule deciding when the view refits can be tested on
// its own (tests/camera.rs runs it in Node.js). Served in front of
// viewer.js, in the same script.
//
// A camera is { yaw, pitch, dist, target: [x, y, z], fov } (radians): it
// orbits `target` at distance `dist`, z up. The viewer remembers the box it
// was last fitted to; when an edit brings a new box, `refitReason` says
// whether to fit again:
//   - "first": nothing was fitted yet;
//   - "size": the new box's diagonal is more than SIZE times larger or
//     smaller than the fitted one's (1.25: a change of more than 25 %);
//   - "moved": its centre moved by more than SHIFT (25 %) of the fitted
//     diagonal;
//   - "out of view": no part of it is on screen with the current camera.
// Otherwise (null) the view stays as the user left it: hand zoom and pan
// survive every edit that keeps the box within those limits of the box the
// view was fitted to (measured against that box, not the previous edit's,
// so many small steps still refit once they add up). A refit keeps the
// user's orbit angles (yaw, pitch) and sets the target and distance only.
"use strict";

(function (root) {
  const SIZE = 1.25;
  const SHIFT = 0.25;
  const FOV = 35 * Math.PI / 180;
  // The solid rarely reaches the box's corners: frame a little tighter
  // than the box's bounding sphere.
  const TIGHT = 0.92;

  function centre(b) { return [0, 1, 2].map((a) => 0.5 * (b[0][a] + b[1][a])); }
  function diagonal(b) { return Math.hypot(b[1][0] - b[0][0], b[1][1] - b[0][1], b[1][2] - b[0][2]); }
  function norm(a) { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

  // The viewing direction and the screen's right and up vectors.
  function axes(yaw, pitch) {
    const cp = Math.cos(pitch), sp = Math.sin(pitch);
    const fwd = [-cp * Math.cos(yaw), -cp * Math.sin(yaw), -sp];
    const right = norm(cross(fwd, [0, 0, 1]));
    const up = cross(right, fwd);
    return { fwd, right, up };
  }

  function eye(cam) {
    const { fwd } = axes(cam.yaw, cam.pitch);
    return [0, 1, 2].map((a) => cam.target[a] - fwd[a] * cam.dist);
  }

  // The distance at which box `b` fills the view.
  function fitDistance(b, fov) {
    return 0.5 * diagonal(b) / Math.sin(0.5 * (fov || FOV)) * TIGHT;
  }

  // The camera fitted to box `b`, looking along the given orbit angles.
  function fit(b, yaw, pitch, fov) {
    const f = fov || FOV;
    return { yaw, pitch, fov: f, target: centre(b), dist: fitDistance(b, f) };
  }

  // Screen coordinates ([-1, 1] across the view) of point `p`, or null
  // when it is behind the camera.
  function project(p, cam, aspect) {
    const { fwd, right, up } = axes(cam.yaw, cam.pitch);
    const e = eye(cam);
    const v = [p[0] - e[0], p[1] - e[1], p[2] - e[2]];
    const z = dot(v, fwd);
    if (!(z > 1e-9 * cam.dist)) return null;
    const t = Math.tan(0.5 * (cam.fov || FOV));
    return [dot(v, right) / (z * t * (aspect || 1)), dot(v, up) / (z * t)];
  }

  // Whether some of box `b` is on screen: the rectangle around its
  // corners' projections overlaps the view (a box reaching behind the
  // camera counts as in view, as the camera is then in or next to it).
  function inView(b, cam, aspect) {
    let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity], behind = 0;
    for (let c = 0; c < 8; c++) {
      const p = [0, 1, 2].map((a) => b[(c >> a) & 1][a]);
      const s = project(p, cam, aspect);
      if (!s) { behind++; continue; }
      for (let k = 0; k < 2; k++) { lo[k] = Math.min(lo[k], s[k]); hi[k] = Math.max(hi[k], s[k]); }
    }
    if (behind === 8) return false;
    if (behind > 0) return true;
    return lo[0] <= 1 && hi[0] >= -1 && lo[1] <= 1 && hi[1] >= -1;
  }

  // Why the view should be fitted to box `next`, given the box it was
  // fitted to and the camera now; null to keep the view.
  function refitReason(fitted, next, cam, aspect) {
    if (!fitted) return "first";
    const d0 = diagonal(fitted), d1 = diagonal(next);
    if (!(d0 > 0) || !(d1 > 0)) return d0 === d1 ? null : "size";
    const s = d1 / d0;
    if (s > SIZE || s < 1 / SIZE) return "size";
    const c0 = centre(fitted), c1 = centre(next);
    if (Math.hypot(c1[0] - c0[0], c1[1] - c0[1], c1[2] - c0[2]) > SHIFT * d0) return "moved";
    if (cam && !inView(next, cam, aspect)) return "out of view";
    return null;
  }

  const api = { SIZE, SHIFT, FOV, centre, diagonal, axes, eye, fitDistance, fit, project, inView, refitReason };
  root.StudioCamera = api;
  if (typeof module === "object" && module && module.exports) module.exports = api;
})(typeof window !== "undefined" ? window : globalThis);
