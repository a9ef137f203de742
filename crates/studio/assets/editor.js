// microfrep studio: the HyperFun editor. A textarea over a highlighted
// copy of its text (same font and metrics), with a gutter of line numbers
// that marks lines with diagnostics. Positions are 1-based line and column
// with a tab counting as one column, as HyperFun reports them.
"use strict";

(function () {
  const KEYWORDS = new Set(["array", "if", "then", "else", "endif", "while", "loop",
    "endloop", "and", "or", "not", "xor"]);

  function escapeHtml(s) {
    return s.replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;");
  }

  // Token classes of one line, one per character.
  function classify(line) {
    const cls = new Array(line.length).fill("");
    let i = 0;
    while (i < line.length) {
      const c = line[i];
      if (c === "-" && line[i + 1] === "-") {
        for (let k = i; k < line.length; k++) cls[k] = "c";
        break;
      }
      if (/[0-9.]/.test(c) && (i === 0 || !/[A-Za-z0-9_]/.test(line[i - 1]))) {
        const m = /^(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?/.exec(line.slice(i));
        if (m) {
          for (let k = i; k < i + m[0].length; k++) cls[k] = "n";
          i += m[0].length;
          continue;
        }
      }
      if (/[A-Za-z_]/.test(c)) {
        const m = /^[A-Za-z_][A-Za-z0-9_]*/.exec(line.slice(i));
        const w = m[0];
        const lw = w.toLowerCase();
        let k = "";
        if (KEYWORDS.has(lw)) k = "k";
        else if (lw.startsWith("hf") || lw.startsWith("mf")) k = "f";
        for (let j = i; j < i + w.length; j++) cls[j] = k;
        i += w.length;
        continue;
      }
      if ("&|\\~@".includes(c)) cls[i] = "o";
      i++;
    }
    return cls;
  }

  class Editor {
    constructor(root) {
      this.root = root;
      this.gutter = root.querySelector(".gutter");
      this.pre = root.querySelector("pre");
      this.ta = root.querySelector("textarea");
      this.diags = [];
      this.listeners = [];
      this.ta.addEventListener("input", () => this.changed());
      this.ta.addEventListener("scroll", () => this.syncScroll());
      this.ta.addEventListener("keydown", (e) => this.key(e));
      this.render();
    }

    onChange(f) { this.listeners.push(f); }

    getText() { return this.ta.value; }

    setText(s) {
      this.ta.value = s;
      this.render();
    }

    changed() {
      this.render();
      for (const f of this.listeners) f(this.ta.value);
    }

    key(e) {
      if (e.key === "Tab" && !e.shiftKey && !e.ctrlKey && !e.metaKey && !e.altKey) {
        e.preventDefault();
        const { selectionStart: a, selectionEnd: b, value } = this.ta;
        this.ta.value = value.slice(0, a) + "  " + value.slice(b);
        this.ta.selectionStart = this.ta.selectionEnd = a + 2;
        this.changed();
      }
    }

    // Diagnostics: [{severity, line, col, message}].
    setDiagnostics(d) {
      this.diags = d || [];
      this.render();
    }

    syncScroll() {
      this.pre.scrollTop = this.ta.scrollTop;
      this.pre.scrollLeft = this.ta.scrollLeft;
      this.gutter.scrollTop = this.ta.scrollTop;
    }

    render() {
      const lines = this.ta.value.split("\n");
      const byLine = new Map();
      for (const d of this.diags) {
        if (!d.line) continue;
        if (!byLine.has(d.line)) byLine.set(d.line, []);
        byLine.get(d.line).push(d);
      }
      let html = "";
      let gut = "";
      lines.forEach((raw, idx) => {
        const line = raw.replace(/\r/g, "");
        const n = idx + 1;
        const cls = classify(line);
        const marks = new Array(line.length + 1).fill("");
        const ds = byLine.get(n) || [];
        for (const d of ds) {
          const at = Math.max(0, Math.min(line.length, d.col - 1));
          let end = at + 1;
          while (end < line.length && /[A-Za-z0-9_.]/.test(line[end]) && /[A-Za-z0-9_.]/.test(line[at])) end++;
          for (let k = at; k < end; k++) marks[k] = d.severity === "error" ? "e" : "w";
        }
        let out = "";
        let run = "";
        let key = null;
        const flush = () => {
          if (!run) return;
          const [c, m] = key.split("/");
          const classes = [c && "t" + c, m && "m" + m].filter(Boolean).join(" ");
          out += classes ? `<span class="${classes}">${escapeHtml(run)}</span>` : escapeHtml(run);
          run = "";
        };
        for (let k = 0; k < line.length; k++) {
          const kk = cls[k] + "/" + marks[k];
          if (kk !== key) { flush(); key = kk; }
          run += line[k];
        }
        flush();
        // An error at the end of the line (or past it) gets a visible mark.
        if (marks[line.length]) out += `<span class="m${marks[line.length]}"> </span>`;
        else if (ds.some((d) => d.col - 1 >= line.length)) out += `<span class="m${ds[0].severity === "error" ? "e" : "w"}"> </span>`;
        html += out + "\n";
        const sev = ds.some((d) => d.severity === "error") ? "err" : ds.length ? "warn" : "";
        const title = ds.map((d) => `${d.line}:${d.col}: ${d.severity}: ${d.message}`).join("\n");
        gut += `<div class="${sev}" title="${escapeHtml(title).replace(/"/g, "&quot;")}">${n}</div>`;
      });
      this.pre.innerHTML = html + " ";
      this.gutter.innerHTML = gut + "<div>&nbsp;</div>";
      this.syncScroll();
    }

    // Puts the caret at a 1-based line and column.
    goTo(line, col) {
      const lines = this.ta.value.split("\n");
      let off = 0;
      for (let i = 0; i < Math.min(line - 1, lines.length); i++) off += lines[i].length + 1;
      off += Math.max(0, col - 1);
      this.ta.focus();
      this.ta.selectionStart = this.ta.selectionEnd = Math.min(off, this.ta.value.length);
      const lh = parseFloat(getComputedStyle(this.ta).lineHeight) || 18;
      this.ta.scrollTop = Math.max(0, (line - 3) * lh);
      this.syncScroll();
    }
  }

  window.StudioEditor = Editor;
})();
