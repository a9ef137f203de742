// microfrep studio: the page. Sends edits, long-polls the session state,
// and shows diagnostics, parameters, meshes, analysis and exports.
"use strict";

(function () {
  const $ = (id) => document.getElementById(id);
  // The studio's token comes in the page's address (`/?token=...`, as the
  // server prints it) and goes with every request: as a header where the
  // page fetches, in the query where the browser does (images, downloads).
  const TOKEN = new URLSearchParams(location.search).get("token") || "";
  const H = { "Content-Type": "application/json", "X-Studio": "1", "X-Studio-Token": TOKEN };
  const withToken = (u) => u + (u.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(TOKEN);

  const app = {
    ready: false,
    session: null,
    posted: 0,         // newest generation this page sent
    version: 0,        // state version seen
    state: null,       // newest state of the posted generation
    shown: { gen: 0, level: -1 },
    params: null,      // [{value, min, max}] of the model on screen
    paramKey: "",      // parameter names, to tell when the set changed
    userBounds: null,
    bounds: null,
    attrNames: [],
    meshLoads: 0,
    sectionTimer: null,
    editTimer: null,
  };
  window.studio = app;

  const editor = new window.StudioEditor($("editor"));
  const viewer = new window.StudioViewer($("canvas"));
  app.editor = editor;
  app.viewer = viewer;
  if (!viewer.ok) {
    $("canvas").classList.add("hidden");
    $("fallback").classList.remove("hidden");
  }

  function fmt(v, d) {
    if (v === null || v === undefined || Number.isNaN(v)) return "–";
    const a = Math.abs(v);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(d === undefined ? 3 : d);
    return v.toFixed(d === undefined ? 4 : d);
  }

  function setStatus(text, kind) {
    const s = $("status");
    s.textContent = text;
    s.className = kind || "";
  }

  async function api(path, body) {
    const r = await fetch(path, body === undefined ? { headers: { "X-Studio-Token": TOKEN } } : { method: "POST", headers: H, body: JSON.stringify(body) });
    const ct = r.headers.get("Content-Type") || "";
    const v = ct.includes("json") ? await r.json() : await r.text();
    if (!r.ok) throw new Error((v && v.error) || v || r.statusText);
    return v;
  }

  // --- edits ---
  function scheduleEdit(delay) {
    clearTimeout(app.editTimer);
    app.editTimer = setTimeout(sendEdit, delay === undefined ? 80 : delay);
  }

  async function sendEdit() {
    const body = {
      session: app.session,
      source: editor.getText(),
      file: $("filename").value || "model.hf",
      object: $("object").value || null,
      // Values the user set; the others follow the model's comment.
      params: app.params ? app.params.map((p) => (p.touched ? p.value : null)) : null,
      bounds: app.userBounds,
      wait_ms: 1500,
    };
    setStatus("lowering…", "busy");
    try {
      const st = await api("/api/edit", body);
      app.posted = Math.max(app.posted, st.latest_gen);
      handle(st);
    } catch (e) {
      setStatus(e.message, "bad");
    }
  }

  editor.onChange(() => scheduleEdit());
  $("filename").addEventListener("change", () => scheduleEdit(0));
  $("object").addEventListener("change", () => { app.params = null; app.userBounds = null; scheduleEdit(0); });

  // --- state ---
  async function poll() {
    for (;;) {
      try {
        const st = await api(`/api/state?session=${app.session}&since=${app.version}&wait_ms=20000`);
        handle(st);
      } catch (e) {
        setStatus("server: " + e.message, "bad");
        await new Promise((r) => setTimeout(r, 1000));
      }
    }
  }

  function handle(st) {
    if (st.version > app.version) app.version = st.version;
    app.posted = Math.max(app.posted, st.latest_gen);
    if (st.gen !== st.latest_gen || st.gen < app.posted) {
      setStatus("working on the newest edit…", "busy");
      return;
    }
    app.state = st;
    showDiagnostics(st);
    if (st.model) {
      showParams(st.model);
      showObjects(st.model);
      showBounds(st.model);
      showAttributes(st.model);
    } else if (st.loaded) {
      $("params").classList.add("hidden");
    }
    showMeshes(st);
    showAnalysis(st);
    const t = st.timings || {};
    if (st.error) setStatus("stopped: " + st.error.split("\n")[0], "bad");
    else if (st.loaded && !st.model) setStatus("errors in the model", "bad");
    else if (st.done) setStatus(`done · first image ${fmt(t.first_mesh_s, 2)} s · refined ${fmt(t.refined_mesh_s, 2)} s`, "ok");
    else setStatus(st.stage + "…", "busy");
  }

  function showDiagnostics(st) {
    const box = $("diagnostics");
    box.textContent = "";
    if (!st.loaded) return;
    editor.setDiagnostics(st.diagnostics);
    const blocks = (st.rendered || "").split(/\n(?=\S)/).filter((b) => b.trim());
    // One block per diagnostic, as `microfrep check` prints them.
    blocks.forEach((text, i) => {
      const d = st.diagnostics[i] || {};
      const div = document.createElement("div");
      div.className = "d " + (d.severity || "error");
      const [head, ...rest] = text.split("\n");
      const hs = document.createElement("span");
      hs.className = "head";
      hs.textContent = head;
      div.appendChild(hs);
      div.appendChild(document.createTextNode(rest.length ? "\n" + rest.join("\n") : ""));
      if (d.line) div.addEventListener("click", () => editor.goTo(d.line, d.col));
      box.appendChild(div);
    });
    for (const w of st.warnings || []) {
      const div = document.createElement("div");
      div.className = "note";
      div.textContent = w;
      box.appendChild(div);
    }
    if (st.error) {
      const div = document.createElement("div");
      div.className = "fail";
      div.textContent = "error: " + st.error;
      box.appendChild(div);
    }
    if (!box.childNodes.length && st.model) {
      const div = document.createElement("div");
      div.className = "okline";
      const m = st.model;
      const parts = (st.parts || []).map((p) =>
        ` · ${p.name} = ${p.source} (${p.kind}${p.cached ? "" : `, built in ${fmt(p.seconds, 2)} s`})`).join("");
      div.textContent = `ok: object ${m.object}${m.lowered ? "" : " (evaluated per point: no interval pruning)"}${parts}`;
      box.appendChild(div);
    }
  }

  function showParams(m) {
    const key = m.object + ":" + m.params.length;
    const list = $("param-list");
    const old = app.params || [];
    // Entries the user touched stay; the others follow the server (the
    // model's comment defaults and ranges).
    app.params = m.params.map((p, i) => {
      const o = old[i];
      if (o && o.touched) return o;
      const st = o || {};
      st.value = p.value;
      if (!st.rangeTouched) { st.min = p.range[0]; st.max = p.range[1]; }
      return st;
    });
    if (key !== app.paramKey || list.childNodes.length !== m.params.length) {
      app.paramKey = key;
      list.textContent = "";
      m.params.forEach((p, i) => {
        const row = document.createElement("div");
        row.className = "p";
        const name = document.createElement("span");
        name.className = "name";
        name.textContent = p.name;
        const lo = document.createElement("input");
        lo.type = "number"; lo.step = "any"; lo.title = "slider minimum";
        const slider = document.createElement("input");
        slider.type = "range"; slider.min = 0; slider.max = 1000;
        slider.setAttribute("aria-label", p.name);
        const hi = document.createElement("input");
        hi.type = "number"; hi.step = "any"; hi.title = "slider maximum";
        const val = document.createElement("input");
        val.type = "number"; val.step = "any"; val.className = "val"; val.title = "value";
        const st = () => app.params[i];
        row.place = () => {
          const s = st();
          const f = (s.value - s.min) / ((s.max - s.min) || 1);
          slider.value = Math.round(1000 * Math.max(0, Math.min(1, f)));
          if (document.activeElement !== val) val.value = +s.value.toPrecision(6);
          if (document.activeElement !== lo) lo.value = +s.min.toPrecision(6);
          if (document.activeElement !== hi) hi.value = +s.max.toPrecision(6);
        };
        slider.addEventListener("input", () => {
          const s = st();
          s.value = +(s.min + (s.max - s.min) * (+slider.value / 1000)).toPrecision(6);
          s.touched = true;
          val.value = s.value;
          scheduleEdit(40);
        });
        val.addEventListener("change", () => {
          const s = st();
          const v = parseFloat(val.value);
          if (!Number.isFinite(v)) return row.place();
          s.value = v; s.touched = true;
          if (v < s.min) { s.min = v; s.rangeTouched = true; }
          if (v > s.max) { s.max = v; s.rangeTouched = true; }
          row.place();
          scheduleEdit(0);
        });
        lo.addEventListener("change", () => {
          const s = st(), v = parseFloat(lo.value);
          if (Number.isFinite(v) && v < s.max) { s.min = v; s.rangeTouched = true; }
          row.place();
        });
        hi.addEventListener("change", () => {
          const s = st(), v = parseFloat(hi.value);
          if (Number.isFinite(v) && v > s.min) { s.max = v; s.rangeTouched = true; }
          row.place();
        });
        row.append(name, lo, slider, hi, val);
        list.appendChild(row);
      });
    }
    for (const row of list.childNodes) row.place();
    $("params").classList.toggle("hidden", m.params.length === 0);
  }

  function showObjects(m) {
    const sel = $("object");
    const want = m.objects.join(",");
    if (sel.dataset.key !== want) {
      sel.dataset.key = want;
      sel.textContent = "";
      for (const o of m.objects) {
        const opt = document.createElement("option");
        opt.value = o; opt.textContent = o;
        sel.appendChild(opt);
      }
    }
    sel.value = m.object;
    $("object-label").classList.toggle("hidden", m.objects.length < 2);
  }

  function showBounds(m) {
    if (!m.bounds) return;
    const b = m.bounds;
    const changed = !app.bounds || JSON.stringify(app.bounds) !== JSON.stringify(b);
    const first = !app.bounds;
    app.bounds = b;
    $("bounds-src").textContent = { page: "(set here)", comment: "(comment)", part: "(the part's box)", proven: "(proven)" }[m.bounds_source] || "";
    if (changed) {
      const box = $("bounds-inputs");
      box.textContent = "";
      ["x", "y", "z"].forEach((n, a) => {
        for (const k of [0, 1]) {
          const inp = document.createElement("input");
          inp.type = "number"; inp.step = "any"; inp.value = +b[k][a].toPrecision(6);
          inp.title = (k ? "max " : "min ") + n;
          inp.addEventListener("change", () => {
            const nb = JSON.parse(JSON.stringify(app.bounds));
            const v = parseFloat(inp.value);
            if (!Number.isFinite(v)) return;
            nb[k][a] = v;
            if (nb[1][a] <= nb[0][a]) return;
            app.userBounds = nb;
            scheduleEdit(0);
          });
          box.appendChild(inp);
        }
      });
      viewer.setBounds(b, first);
      if (first) viewer.resetView("iso");
      updateSectionRange();
      const ext = [0, 1, 2].map((a) => b[1][a] - b[0][a]);
      if (!$("sl-layer").value) $("sl-layer").value = +(ext[2] / 100).toPrecision(3);
      if (!$("sl-pixel").value) $("sl-pixel").value = +(Math.max(ext[0], ext[1]) / 400).toPrecision(3);
    }
  }

  function showAttributes(m) {
    const names = m.attributes || [];
    if (names.join(",") !== app.attrNames.join(",")) {
      app.attrNames = names;
      const sel = $("colour");
      sel.textContent = "";
      const plain = document.createElement("option");
      plain.value = -1; plain.textContent = "shading";
      sel.appendChild(plain);
      names.forEach((n, i) => {
        const o = document.createElement("option");
        o.value = i; o.textContent = n;
        sel.appendChild(o);
      });
      viewer.setAttribute(-1);
    }
    $("colour-label").classList.toggle("hidden", names.length === 0);
  }

  $("colour").addEventListener("change", () => applyColour());
  function applyColour() {
    const k = +$("colour").value;
    const m = app.state && app.state.meshes.find((x) => x.level === app.shown.level);
    const r = m && m.attribute_ranges[k];
    viewer.setAttribute(k, r ? [r[0], r[1] > r[0] ? r[1] : r[0] + 1] : undefined);
  }

  async function showMeshes(st) {
    if (!st.meshes.length) {
      if (st.done) $("viewinfo").textContent = viewer.mesh ? "no new mesh (showing the last one)" : "no mesh";
      return;
    }
    const best = st.meshes.reduce((a, b) => (b.level > a.level ? b : a));
    if (app.shown.gen === st.gen && app.shown.level >= best.level) return;
    const want = { gen: st.gen, level: best.level };
    app.shown = want;
    const note = best.note ? " · " + best.note : "";
    const label = `${best.resolution}³ cells · ${best.triangles.toLocaleString()} triangles · ${fmt(best.seconds, 2)} s${note}`;
    if (!viewer.ok) {
      showFallback(st.gen);
      $("viewinfo").textContent = label;
      return;
    }
    try {
      const r = await fetch(best.url, { headers: { "X-Studio-Token": TOKEN } });
      if (!r.ok) throw new Error(await r.text());
      const buf = await r.arrayBuffer();
      if (app.shown.gen !== want.gen || app.shown.level !== want.level) return;
      viewer.setMesh(buf);
      applyColour();
      app.meshLoads++;
      $("viewinfo").textContent = label;
      refreshSectionImage();
    } catch (e) {
      $("viewinfo").textContent = "mesh: " + e.message;
    }
  }

  function showFallback(gen) {
    const img = $("fallback");
    const w = Math.min(1600, img.clientWidth || 800), h = Math.min(1200, img.clientHeight || 600);
    const view = app.fallbackView || "iso";
    img.src = withToken(`/api/render.png?session=${app.session}&gen=${gen}&view=${view}&cutaway=${$("cutaway").checked ? 1 : 0}&w=${w}&h=${h}`);
  }

  function row(name, value, err) {
    const a = document.createElement("span");
    a.textContent = name;
    const b = document.createElement("span");
    b.className = "v";
    b.textContent = value + (err !== undefined ? " ± " + (err > 0 ? err.toPrecision(2) : "0") : "");
    return [a, b];
  }

  function showAnalysis(st) {
    const body = $("analysis-body");
    const a = st.analysis.refined || st.analysis.preview;
    if (!a) {
      if (st.loaded && !st.model) body.textContent = "no figures: the model has errors";
      else if (st.error) body.textContent = "no figures";
      else body.textContent = "measuring…";
      body.className = "muted";
      return;
    }
    const r = a.report;
    body.textContent = "";
    body.className = "";
    const kind = st.analysis.refined ? "refined" : "preview";
    const head = document.createElement("div");
    head.className = "res";
    head.textContent = `${kind}, ${a.resolution} voxels on the longest side${kind === "preview" && !st.done ? " (refining…)" : ""}`;
    body.appendChild(head);
    const t = document.createElement("div");
    t.className = "figs";
    const rows = [
      row("volume fraction", fmt(r.volume_fraction.value), r.volume_fraction.error),
      row("porosity", fmt(r.porosity.value), r.porosity.error),
      row("volume", fmt(r.volume.value), r.volume.error),
      row("surface area", fmt(r.area.value), r.area.error),
      row("specific surface", fmt(r.specific_surface.value), r.specific_surface.error),
    ];
    const c = r.connectivity;
    if (c) {
      const yn = (b) => (b ? "yes" : "no");
      rows.push(
        row("solid components", String(c.solid_components)),
        row("pore components", String(c.pore_components)),
        row("open pores", fmt(100 * c.open_pore_fraction, 2) + " %"),
        row("closed pores", String(c.closed_pores)),
        row("percolation x y z", `${yn(c.percolates.x)} ${yn(c.percolates.y)} ${yn(c.percolates.z)}`),
        row("Euler (surface)", String(c.euler_surface)),
      );
    }
    for (const [a, b] of rows) t.append(a, b);
    body.appendChild(t);
    body.dataset.volumeFraction = r.volume_fraction.value;
    body.dataset.kind = kind;
  }

  // --- view controls ---
  document.querySelectorAll("[data-view]").forEach((b) =>
    b.addEventListener("click", () => {
      app.fallbackView = b.dataset.view;
      viewer.resetView(b.dataset.view);
      if (!viewer.ok && app.state) showFallback(app.state.gen);
    }));
  $("cutaway").addEventListener("change", () => {
    viewer.setCutaway($("cutaway").checked);
    if (!viewer.ok && app.state) showFallback(app.state.gen);
  });

  function sectionValue() {
    const a = +$("sec-axis").value;
    if (a < 0 || !app.bounds) return 0;
    const b = app.bounds;
    return b[0][a] + (b[1][a] - b[0][a]) * (+$("sec-pos").value / 1000);
  }

  function updateSectionRange() {
    const a = +$("sec-axis").value;
    $("sec-pos").disabled = a < 0;
    const v = sectionValue();
    $("sec-val").textContent = a < 0 ? "" : ["x", "y", "z"][a] + " = " + fmt(v, 3);
    viewer.setSection(a, v, $("sec-flip").checked);
    refreshSectionImage();
  }

  viewer.onSectionDrag = (v) => {
    const a = +$("sec-axis").value;
    const b = app.bounds;
    $("sec-pos").value = Math.round(1000 * (v - b[0][a]) / (b[1][a] - b[0][a]));
    updateSectionRange();
  };
  $("sec-axis").addEventListener("change", () => {
    // Cut away the side facing the viewer, so the cut face shows.
    const a = +$("sec-axis").value;
    if (a >= 0) $("sec-flip").checked = viewer.eye()[a] < sectionValue();
    updateSectionRange();
  });
  for (const id of ["sec-flip", "sec-map"]) $(id).addEventListener("change", updateSectionRange);
  $("sec-pos").addEventListener("input", updateSectionRange);

  function refreshSectionImage() {
    clearTimeout(app.sectionTimer);
    const a = +$("sec-axis").value;
    if (a < 0 || !$("sec-map").checked || !app.state || !app.bounds) {
      viewer.setSectionImage(null);
      return;
    }
    app.sectionTimer = setTimeout(() => {
      const b = app.bounds;
      const [ra, ua] = a === 0 ? [1, 2] : a === 1 ? [0, 2] : [0, 1];
      const er = b[1][ra] - b[0][ra], eu = b[1][ua] - b[0][ua];
      const long = 384;
      const w = er >= eu ? long : Math.max(8, Math.round(long * er / eu));
      const h = eu >= er ? long : Math.max(8, Math.round(long * eu / er));
      const v = sectionValue();
      const img = new Image();
      img.onload = () => {
        if (+$("sec-axis").value === a && Math.abs(sectionValue() - v) < 1e-12) viewer.setSectionImage(img, a, v);
      };
      img.src = withToken(`/api/section.png?session=${app.session}&gen=${app.state.gen}&axis=${a}&value=${v}&w=${w}&h=${h}`);
    }, 120);
  }

  $("bounds-auto").addEventListener("click", () => { app.userBounds = null; scheduleEdit(0); });

  // --- files and exports ---
  function download(url) {
    const a = document.createElement("a");
    a.href = url;
    a.download = "";
    document.body.appendChild(a);
    a.click();
    a.remove();
  }
  function msg(t) { $("export-msg").textContent = t; }

  $("exp-stl").addEventListener("click", () => {
    if (!app.state || !app.state.meshes.length) return msg("no mesh yet");
    download(withToken(`/api/export.stl?session=${app.session}&gen=${app.state.gen}`));
    msg("STL of the finest mesh so far");
  });
  $("exp-zip").addEventListener("click", () => {
    if (!app.state) return;
    const q = `layer=${encodeURIComponent($("sl-layer").value)}&pixel=${encodeURIComponent($("sl-pixel").value)}&format=${$("sl-format").value}`;
    download(withToken(`/api/slices.zip?session=${app.session}&gen=${app.state.gen}&${q}`));
    msg("slicing… the download starts when the stack is made");
  });
  $("exp-dir").addEventListener("click", async () => {
    if (!app.state) return;
    try {
      const r = await api("/api/slices", {
        session: app.session, gen: app.state.gen, dir: $("sl-dir").value,
        layer: parseFloat($("sl-layer").value), pixel: parseFloat($("sl-pixel").value), format: $("sl-format").value,
      });
      msg(`wrote ${r.layers} layers to ${r.written}/`);
    } catch (e) { msg(e.message); }
  });
  $("exp-hf").addEventListener("click", () => {
    const blob = new Blob([editor.getText()], { type: "text/plain" });
    const url = URL.createObjectURL(blob);
    const a = document.createElement("a");
    a.href = url;
    a.download = ($("filename").value.split("/").pop() || "model.hf");
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 1000);
  });
  $("save").addEventListener("click", async () => {
    try {
      const r = await api("/api/save", { path: $("filename").value, source: editor.getText() });
      setStatus("saved " + r.saved, "ok");
      loadFiles();
    } catch (e) { setStatus(e.message, "bad"); }
  });

  function fillFiles(files) {
    const sel = $("files");
    sel.textContent = "";
    const first = document.createElement("option");
    first.value = ""; first.textContent = "open…";
    sel.appendChild(first);
    for (const f of files) {
      const o = document.createElement("option");
      o.value = f; o.textContent = f;
      sel.appendChild(o);
    }
  }
  async function loadFiles() {
    try { fillFiles((await api("/api/files")).files); } catch (e) { /* keep the list */ }
  }
  $("files").addEventListener("change", async () => {
    const f = $("files").value;
    if (!f) return;
    try {
      const src = await api(`/api/file?path=${encodeURIComponent(f)}`);
      openModel(f, src);
    } catch (e) { setStatus(e.message, "bad"); }
    $("files").value = "";
  });

  function openModel(name, src) {
    $("filename").value = name;
    app.params = null;
    app.paramKey = "";
    app.userBounds = null;
    app.bounds = null;
    $("object").value = "";
    $("object").dataset.key = "";
    $("object").textContent = "";
    editor.setText(src);
    scheduleEdit(0);
  }

  // Test hooks: replace the text as a user would (input events).
  app.setSource = (src) => { editor.setText(src); editor.changed(); };
  app.openModel = openModel;

  (async function boot() {
    if (!TOKEN) {
      setStatus("no token in the address: open the address microfrep serve printed (…/?token=…)", "bad");
      return;
    }
    try {
      const s = await api("/api/session", {});
      app.session = s.session;
      fillFiles(s.files);
      openModel(s.file, s.source);
      app.ready = true;
      poll();
    } catch (e) {
      setStatus("cannot start a session: " + e.message, "bad");
    }
  })();
})();
