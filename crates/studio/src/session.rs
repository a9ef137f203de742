//! Per-tab sessions: the latest edit, its generation, and the results a
//! worker thread makes for it stage by stage (lowering, bounds, a probe of
//! the evaluation cost, meshes from coarse to fine, analysis from quick to
//! refined).
//!
//! A session has one worker at a time. An edit bumps the session's
//! generation counter and leaves the edit for the worker; every long call
//! of the worker checks the counter between units of work (a brick, a
//! layer) and unwinds when it is stale (`Guard::check`), so the worker
//! turns to the newest edit within one unit of work. Lowering cannot be
//! interrupted, but HyperFun bounds its loops. Each stage also has a time
//! limit, and a panic in a stage is caught and shown as the model's error.

use crate::engine::{self, Diag, Loaded, MeshData};
use crate::error::StudioError;
use crate::hints;
use crate::parts::{Bound, Parts};
use crate::wire;
use microfrep_core::{Field, Shape};
use serde_json::{json, Value};
use std::collections::HashMap;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Stack of the session workers and probes, which lower and evaluate the
/// model. HyperFun's lowering and its per-point interpreter move to fresh
/// heap segments when their stack runs low (`stacker`), and expression
/// graphs are dropped without recursion, so this need not grow with the
/// model; it is reserved address space, which `ulimit -v` counts.
pub(crate) const WORKER_STACK: usize = 16 << 20;

/// What the workers may spend and how they refine.
#[derive(Clone, Debug)]
pub struct Config {
    /// Mesh resolutions (cells on the longest side), coarse to fine.
    pub levels: Vec<usize>,
    /// Analysis resolutions: the quick one after the first mesh, the
    /// refined one once the model has settled.
    pub analysis: [usize; 2],
    /// Time limit of one stage (a mesh level, an analysis, an export).
    pub job_seconds: f64,
    /// Most bytes one mesh or analysis may need.
    pub memory_limit: f64,
    /// Quiet time after an edit before the refining stages start.
    pub settle: Duration,
    /// Seconds the evaluation probe may take.
    pub probe_seconds: f64,
    /// Most sessions at once.
    pub max_sessions: usize,
    /// Data fields bound for every model, `(NAME, SOURCE)`
    /// ([`crate::ServeOptions::fields`]).
    pub fields: Vec<(String, String)>,
}

/// The reason a guarded job stopped early (the unwind payload).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Abort {
    /// A newer edit arrived.
    Stale,
    /// The stage ran past its time limit.
    Timeout,
    /// The client of the request closed its connection.
    Gone,
}

/// Stops a job that is stale or over time, by unwinding from inside the
/// engine's progress callbacks.
pub(crate) struct Guard {
    gen: Option<(Arc<AtomicU64>, u64)>,
    deadline: Instant,
    pub(crate) limit: f64,
    /// The connection of the request the job answers.
    client: Option<crate::conn::Watch>,
}

impl Guard {
    /// A guard for generation `mine` of `gen`, `limit` seconds from now.
    pub(crate) fn new(gen: Option<(Arc<AtomicU64>, u64)>, limit: f64) -> Guard {
        Guard {
            gen,
            deadline: Instant::now() + Duration::from_secs_f64(limit),
            limit,
            client: None,
        }
    }

    /// Also stops when the request's client goes away.
    pub(crate) fn for_client(mut self, client: Option<crate::conn::Watch>) -> Guard {
        self.client = client;
        self
    }

    pub(crate) fn stale(&self) -> bool {
        self.gen
            .as_ref()
            .is_some_and(|(g, mine)| g.load(Ordering::Relaxed) != *mine)
    }

    /// Unwinds with [`Abort`] when stale or past the deadline.
    pub(crate) fn check(&self) {
        if self.stale() {
            resume_unwind(Box::new(Abort::Stale));
        }
        if Instant::now() > self.deadline {
            resume_unwind(Box::new(Abort::Timeout));
        }
        if self.client.as_ref().is_some_and(|c| c.gone()) {
            resume_unwind(Box::new(Abort::Gone));
        }
    }
}

/// Runs `f` under a guard: an [`Abort`] becomes [`StudioError::Stale`] or
/// [`StudioError::Timeout`], any other panic [`StudioError::Panic`].
pub(crate) fn guarded<T>(
    guard: &Guard,
    f: impl FnOnce(&(dyn Fn() + Sync)) -> Result<T, StudioError>,
) -> Result<T, StudioError> {
    let check = || guard.check();
    match catch_unwind(AssertUnwindSafe(|| f(&check))) {
        Ok(r) => r,
        Err(p) => Err(match p.downcast_ref::<Abort>() {
            Some(Abort::Stale) => StudioError::Stale,
            Some(Abort::Timeout) => StudioError::Timeout(guard.limit),
            Some(Abort::Gone) => StudioError::Gone,
            None => StudioError::Panic(panic_message(&p)),
        }),
    }
}

/// The message of a caught panic.
pub(crate) fn panic_message(p: &Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a job panicked".into()
    }
}

/// An edit from the page.
#[derive(Clone, Debug)]
pub struct Edit {
    /// HyperFun source.
    pub source: String,
    /// File name for diagnostics.
    pub file: String,
    /// Object to evaluate (default `my_model`, else the first).
    pub object: Option<String>,
    /// `a[1..]` values; a missing or `None` entry takes the comment's
    /// default (else 0).
    pub params: Option<Vec<Option<f64>>>,
    /// Box to work in; `None` uses the comment hint, else the bound parts'
    /// box where intervals prove the model inside it, else proven bounds.
    pub bounds: Option<[[f64; 3]; 2]>,
    /// Data fields to bind as `(NAME, SOURCE)`, besides (and before) the
    /// comments' `--field NAME=SOURCE`; sources are relative to the working
    /// directory.
    pub fields: Vec<(String, String)>,
    /// When the server received it.
    pub received: Instant,
}

/// One finished mesh level.
pub struct MeshLevel {
    /// Index into [`Config::levels`].
    pub level: usize,
    /// The mesh.
    pub data: MeshData,
    /// The page's blob of it.
    pub blob: Vec<u8>,
    /// Seconds it took.
    pub seconds: f64,
}

/// A parameter as the page shows it.
#[derive(Clone, Debug)]
struct Param {
    value: f64,
    range: [f64; 2],
}

/// Everything known about the current generation.
#[derive(Default)]
struct Current {
    gen: u64,
    source: String,
    file: String,
    received: Option<Instant>,
    /// Lowering finished (diagnostics are final).
    loaded: bool,
    diags: Vec<Diag>,
    rendered: String,
    model: Option<Loaded>,
    params: Vec<Param>,
    bounds: Option<[[f64; 3]; 2]>,
    bounds_source: &'static str,
    parts: Vec<Bound>,
    warnings: Vec<String>,
    meshes: Vec<Arc<MeshLevel>>,
    analysis: Vec<(&'static str, usize, Value)>,
    stage: String,
    error: Option<String>,
    done: bool,
    timings: Vec<(&'static str, f64)>,
}

struct State {
    version: u64,
    pending: Option<(u64, Edit)>,
    worker: bool,
    cur: Current,
    last_seen: Instant,
}

/// One tab's state.
pub struct Session {
    /// The session's id.
    pub id: String,
    gen: Arc<AtomicU64>,
    state: Mutex<State>,
    cond: Condvar,
    cfg: Arc<Config>,
    parts: Arc<Parts>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a finished generation's export needs: its shape and box.
#[derive(Clone)]
pub struct Snapshot {
    /// Generation.
    pub gen: u64,
    /// The model.
    pub shape: Shape,
    /// Box the studio works in.
    pub bounds: [[f64; 3]; 2],
    /// File name of the model.
    pub file: String,
    /// Finished meshes.
    pub meshes: Vec<Arc<MeshLevel>>,
    /// The model's source.
    pub source: String,
}

impl Session {
    fn new(id: String, cfg: Arc<Config>, parts: Arc<Parts>) -> Session {
        Session {
            parts,
            id,
            gen: Arc::new(AtomicU64::new(0)),
            state: Mutex::new(State {
                version: 0,
                pending: None,
                worker: false,
                cur: Current::default(),
                last_seen: Instant::now(),
            }),
            cond: Condvar::new(),
            cfg,
        }
    }

    /// Queues an edit as the newest generation and returns its number;
    /// the work on older generations stops at its next check.
    pub fn edit(self: &Arc<Self>, edit: Edit) -> Result<u64, StudioError> {
        let mut st = lock(&self.state);
        // Numbered under the lock, so the pending edit is always the newest.
        let gen = self.gen.fetch_add(1, Ordering::SeqCst) + 1;
        st.last_seen = Instant::now();
        st.pending = Some((gen, edit));
        if !st.worker {
            st.worker = true;
            let me = self.clone();
            let spawned = std::thread::Builder::new()
                .name(format!("studio-{}", self.id))
                .stack_size(WORKER_STACK)
                .spawn(move || me.work());
            if let Err(e) = spawned {
                st.worker = false;
                return Err(StudioError::Panic(format!("cannot start a worker: {e}")));
            }
        }
        self.cond.notify_all();
        Ok(gen)
    }

    /// The worker: takes the newest edit until none is left.
    fn work(self: Arc<Self>) {
        loop {
            let next = {
                let mut st = lock(&self.state);
                match st.pending.take() {
                    Some(p) => p,
                    None => {
                        st.worker = false;
                        return;
                    }
                }
            };
            let (gen, edit) = next;
            if self.gen.load(Ordering::SeqCst) != gen {
                continue;
            }
            // A panic outside the guarded stages must not leave the session
            // without a worker.
            let r = catch_unwind(AssertUnwindSafe(|| self.run(gen, edit)));
            if let Err(p) = r {
                let msg = panic_message(&p);
                self.publish(gen, |c| {
                    c.error = Some(format!("internal error: {msg}"));
                    c.done = true;
                });
            }
        }
    }

    /// Changes the current generation's results if it is still `gen`, and
    /// wakes the pollers.
    fn publish(&self, gen: u64, f: impl FnOnce(&mut Current)) -> bool {
        let mut st = lock(&self.state);
        if st.cur.gen != gen {
            return false;
        }
        f(&mut st.cur);
        st.version += 1;
        self.cond.notify_all();
        true
    }

    fn guard(&self, gen: u64) -> Guard {
        Guard::new(Some((self.gen.clone(), gen)), self.cfg.job_seconds)
    }

    /// Records a stage's failure; false when the generation went stale
    /// (nothing to show).
    fn fail(&self, gen: u64, e: StudioError) -> bool {
        if matches!(e, StudioError::Stale) {
            return false;
        }
        self.publish(gen, |c| {
            c.error = Some(e.to_string());
            c.stage = "stopped".into();
            c.done = true;
        });
        false
    }

    fn elapsed(&self, gen: u64, what: &'static str) {
        self.publish(gen, |c| {
            if let Some(t) = c.received {
                c.timings.push((what, t.elapsed().as_secs_f64()));
            }
        });
    }

    /// All stages of one generation.
    fn run(&self, gen: u64, edit: Edit) {
        {
            let mut st = lock(&self.state);
            st.cur = Current {
                gen,
                source: edit.source.clone(),
                file: edit.file.clone(),
                received: Some(edit.received),
                stage: "lowering".into(),
                ..Current::default()
            };
            st.version += 1;
            self.cond.notify_all();
        }
        let hint_params = hints::param_hints(&edit.source);
        let given = edit.params.clone().unwrap_or_default();
        let n = hint_params
            .iter()
            .map(|h| h.index)
            .max()
            .unwrap_or(0)
            .max(given.len());
        let params: Vec<f64> = (0..n)
            .map(|k| {
                given.get(k).copied().flatten().unwrap_or_else(|| {
                    hint_params
                        .iter()
                        .find(|h| h.index == k + 1)
                        .map_or(0.0, |h| h.value)
                })
            })
            .collect();
        // Data fields the model calls by name: the edit's, the server's,
        // then the comments' (built once per server; see `parts`); the
        // server's may lie outside the working directory.
        let mut specs: Vec<(String, String, bool)> = Vec::new();
        let given = edit.fields.iter().map(|(n, s)| (n, s, false));
        let server = self.cfg.fields.iter().map(|(n, s)| (n, s, true));
        let comments = hints::field_hints(&edit.source);
        for (n, s, trusted) in given
            .chain(server)
            .chain(comments.iter().map(|(n, s)| (n, s, false)))
        {
            if !specs.iter().any(|(m, _, _)| m.eq_ignore_ascii_case(n)) {
                specs.push((n.clone(), s.clone(), trusted));
            }
        }
        let mut bound: Vec<Bound> = Vec::new();
        let mut full: Vec<(usize, std::sync::mpsc::Receiver<Result<Bound, StudioError>>)> =
            Vec::new();
        if !specs.is_empty() {
            self.publish(gen, |c| c.stage = "reading parts".into());
            for (name, spec, trusted) in &specs {
                let trusted = *trusted;
                let shown = AtomicU64::new(u64::MAX);
                let progress = |stage: &str, done: u64, total: u64| {
                    let pct = (100 * done).checked_div(total).unwrap_or(0).min(100);
                    if shown.swap(pct, Ordering::Relaxed) != pct {
                        self.publish(gen, |c| {
                            c.stage = format!("building {name}={spec}: {stage} {pct} %")
                        });
                    }
                };
                // A large scan not built yet: a coarse stand-in now, the
                // full scan on its own thread, taken after the first image.
                let got = match self.parts.coarse_step(name, spec, trusted) {
                    Some(step) => {
                        let coarse = self.parts.get_coarse(name, spec, trusted, step, &progress);
                        // Started once the stand-in is built, not to slow it.
                        let (parts, n, sp) = (self.parts.clone(), name.clone(), spec.clone());
                        let (tx, rx) = std::sync::mpsc::channel();
                        let spawned = std::thread::Builder::new()
                            .name("studio-part".into())
                            .spawn(move || {
                                let _ = tx.send(parts.get(&n, &sp, trusted, &|_, _, _| {}));
                            });
                        match (coarse, spawned) {
                            (Ok(b), Ok(_)) => {
                                full.push((bound.len(), rx));
                                Ok(b)
                            }
                            _ => self.parts.get(name, spec, trusted, &progress),
                        }
                    }
                    None => self.parts.get(name, spec, trusted, &progress),
                };
                match got {
                    Ok(b) => bound.push(b),
                    Err(e) => {
                        let msg = e.to_string();
                        self.publish(gen, |c| {
                            c.loaded = true;
                            c.rendered = format!("{}: error: {msg}\n", edit.file);
                            c.diags = vec![Diag {
                                error: true,
                                line: 0,
                                col: 0,
                                message: msg,
                            }];
                            c.stage = "errors".into();
                            c.done = true;
                        });
                        return;
                    }
                }
            }
            let b2 = bound.clone();
            self.publish(gen, |c| c.parts = b2);
            self.elapsed(gen, "parts_s");
        }
        let fields: Vec<(String, Arc<dyn Field>)> = bound
            .iter()
            .map(|b| (b.name.clone(), b.part.field.clone()))
            .collect();
        let loaded = engine::load(
            &edit.source,
            &edit.file,
            edit.object.as_deref(),
            &params,
            &fields,
        );
        let Some(model) = loaded.model else {
            self.publish(gen, |c| {
                c.loaded = true;
                c.diags = loaded.diags;
                c.rendered = loaded.rendered;
                c.stage = "errors".into();
                c.done = true;
            });
            return;
        };
        let shape = model.shape.clone();
        let shown: Vec<Param> = model
            .params
            .iter()
            .enumerate()
            .map(|(k, (_, v))| {
                let h = hint_params.iter().find(|h| h.index == k + 1);
                Param {
                    value: *v,
                    range: hints::default_range(h.map_or(*v, |h| h.value), h.and_then(|h| h.range)),
                }
            })
            .collect();
        let lowered = model.lowered;
        self.publish(gen, |c| {
            c.loaded = true;
            c.diags = loaded.diags;
            c.rendered = loaded.rendered;
            c.model = Some(model);
            c.params = shown;
            c.stage = "bounds".into();
        });
        self.elapsed(gen, "lowered_s");

        // The box: the page's, the comment's, the parts', or what
        // intervals prove.
        let Some((mut bounds, source)) = self.find_bounds(gen, &edit, &shape, &bound) else {
            return;
        };
        if !(0..3).all(|a| bounds[0][a].is_finite() && bounds[1][a] > bounds[0][a]) {
            self.fail(
                gen,
                StudioError::Request(format!("the box {bounds:?} is empty or not finite")),
            );
            return;
        }
        self.publish(gen, |c| {
            c.bounds = Some(bounds);
            c.bounds_source = source;
            c.stage = "probe".into();
        });

        // A probe of the evaluation: run-time errors, and the cost per point
        // of models evaluated point by point.
        let probe = match self.probe(gen, &shape, bounds) {
            Ok(p) => p,
            Err(e) => {
                self.fail(gen, e);
                return;
            }
        };
        let warnings: Vec<String> = probe
            .errors
            .iter()
            .map(|(m, l, c, n)| {
                let at = if *l > 0 {
                    format!("{}:{l}:{c}: ", edit.file)
                } else {
                    String::new()
                };
                format!(
                    "{at}run-time error: {m} (at {n} of {} probe points; those points are outside)",
                    probe.points
                )
            })
            .collect();
        let notes = bound.iter().flat_map(|b| {
            b.part
                .notes
                .iter()
                .map(move |n| format!("{}={}: {n}", b.name, b.spec))
        });
        let warnings: Vec<String> = notes.chain(warnings).collect();
        self.publish(gen, |c| c.warnings = warnings);
        let spp = probe.seconds_per_point;
        let threads = rayon::current_num_threads().max(1) as f64;
        // Resolution whose dense sampling fits half the time limit, for
        // models without interval pruning.
        let affordable = |res: usize| -> usize {
            if lowered {
                return res;
            }
            let pts = 0.5 * self.cfg.job_seconds * threads / spp.max(1e-9);
            let fit = pts.cbrt() as usize;
            res.min(fit.saturating_sub(1))
        };

        let levels = self.cfg.levels.clone();
        let aff = &affordable;
        let mut shape = shape;
        let mesh_at = |shape: &Shape, bounds, i: usize| {
            self.mesh_level(gen, shape, bounds, i, levels[i], aff(levels[i]), spp)
        };
        if !mesh_at(&shape, bounds, 0) {
            return;
        }
        // Coarse stand-ins showed the first image: now the full parts.
        if !full.is_empty() {
            match self.full_parts(gen, &edit, &params, bound, full) {
                Some((model, parts)) => {
                    shape = model.shape.clone();
                    if source == "part" {
                        match self.find_bounds(gen, &edit, &shape, &parts) {
                            Some((b, _)) => bounds = b,
                            None => return,
                        }
                    }
                    self.publish(gen, |c| {
                        c.model = Some(model);
                        c.parts = parts;
                        c.bounds = Some(bounds);
                    });
                    self.elapsed(gen, "full_parts_s");
                }
                None => return,
            }
        }
        if !self.analyse(gen, &shape, bounds, affordable(self.cfg.analysis[0]), 0) {
            return;
        }
        // Refinement starts once the model has not changed for a while.
        if !self.settle(gen, edit.received) {
            return;
        }
        for i in 1..levels.len() {
            if !mesh_at(&shape, bounds, i) {
                return;
            }
            if i == 1 && !self.analyse(gen, &shape, bounds, affordable(self.cfg.analysis[1]), 1) {
                return;
            }
        }
        if levels.len() == 1
            && !self.analyse(gen, &shape, bounds, affordable(self.cfg.analysis[1]), 1)
        {
            return;
        }
        self.publish(gen, |c| {
            c.stage = "done".into();
            c.done = true;
        });
    }

    /// The box of generation `gen`: the edit's, a `Box` comment's, the
    /// parts' ([`Session::part_box`]), else what intervals prove (padded);
    /// None when the search failed (the failure is published).
    fn find_bounds(
        &self,
        gen: u64,
        edit: &Edit,
        shape: &Shape,
        bound: &[Bound],
    ) -> Option<([[f64; 3]; 2], &'static str)> {
        if let Some(b) = edit.bounds {
            return Some((b, "page"));
        }
        if let Some(b) = hints::box_hint(&edit.source) {
            return Some((b, "comment"));
        }
        if let Some(b) = self.part_box(gen, shape, bound) {
            return Some((b, "part"));
        }
        let g = Arc::new(self.guard(gen));
        let g2 = g.clone();
        let check: Arc<dyn Fn() + Send + Sync> = Arc::new(move || g2.check());
        match guarded(&g, |_| Ok(engine::prove_bounds(shape, check)?)) {
            Ok(b) => Some((pad(b), "proven")),
            Err(e) => {
                self.fail(gen, e);
                None
            }
        }
    }

    /// Waits for the full builds of parts that came as coarse stand-ins
    /// (`full`: index into `bound`, and the build's reply) and lowers the
    /// model again with them; None when the generation went stale or
    /// failed (the failure is published).
    fn full_parts(
        &self,
        gen: u64,
        edit: &Edit,
        params: &[f64],
        mut bound: Vec<Bound>,
        full: Vec<(usize, std::sync::mpsc::Receiver<Result<Bound, StudioError>>)>,
    ) -> Option<(Loaded, Vec<Bound>)> {
        for (i, rx) in full {
            let what = format!("{}={}", bound[i].name, bound[i].spec);
            self.publish(gen, |c| {
                c.stage = format!("building {what} (the first image was of a coarse stand-in)")
            });
            let r = loop {
                match rx.recv_timeout(Duration::from_millis(100)) {
                    Ok(r) => break r,
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                        if self.gen.load(Ordering::SeqCst) != gen {
                            // The build goes on and is kept for the next edit.
                            return None;
                        }
                    }
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                        break Err(StudioError::Panic(format!("the build of {what} stopped")));
                    }
                }
            };
            match r {
                Ok(b) => bound[i] = b,
                Err(e) => {
                    self.fail(gen, e);
                    return None;
                }
            }
        }
        let fields: Vec<(String, Arc<dyn Field>)> = bound
            .iter()
            .map(|b| (b.name.clone(), b.part.field.clone()))
            .collect();
        let loaded = engine::load(
            &edit.source,
            &edit.file,
            edit.object.as_deref(),
            params,
            &fields,
        );
        match loaded.model {
            Some(m) => Some((m, bound)),
            None => {
                self.fail(
                    gen,
                    StudioError::Request(format!(
                        "the model did not lower with the full parts: {}",
                        loaded.rendered
                    )),
                );
                None
            }
        }
    }

    /// The bound parts' box (their union, padded as proven bounds are),
    /// when intervals prove the model empty outside it: a model cut to its
    /// part gets its box at once instead of after a bounds search, which
    /// costs a mesh field's distance queries by the hundred thousand.
    fn part_box(&self, gen: u64, shape: &Shape, bound: &[Bound]) -> Option<[[f64; 3]; 2]> {
        let first = bound.first()?;
        let hull = bound[1..].iter().fold(first.part.bounds, |h, b| {
            let p = b.part.bounds;
            [
                std::array::from_fn(|a| h[0][a].min(p[0][a])),
                std::array::from_fn(|a| h[1][a].max(p[1][a])),
            ]
        });
        let hint = pad(hull);
        let g = self.guard(gen);
        let r = guarded(&g, |check| {
            Ok(engine::empty_outside(shape, hint, PART_BOX_EVALS, check))
        });
        matches!(r, Ok(true)).then_some(hint)
    }

    /// Mesh level `i` at `res` cells (`want` asked); false when the
    /// generation stopped.
    #[allow(clippy::too_many_arguments)]
    fn mesh_level(
        &self,
        gen: u64,
        shape: &Shape,
        bounds: [[f64; 3]; 2],
        i: usize,
        want: usize,
        res: usize,
        spp: f64,
    ) -> bool {
        if res < 8 {
            return self.fail(
                gen,
                StudioError::Engine(engine::EngineError::Limit(format!(
                    "the model is evaluated point by point at {:.3} ms a point: even a \
                     coarse preview would take longer than the time limit",
                    1e3 * spp
                ))),
            );
        }
        if i > 0 && self.already_at(gen, res) {
            return true;
        }
        self.publish(gen, |c| c.stage = format!("meshing at {res}"));
        let t = Instant::now();
        let g = self.guard(gen);
        let limit = self.cfg.memory_limit;
        let r = guarded(&g, |check| {
            Ok(engine::mesh(shape, bounds, res, limit, check)?)
        });
        let mut data = match r {
            Ok(d) => d,
            Err(e) => return self.fail(gen, e),
        };
        if res < want && data.note.is_none() {
            data.note = Some(format!(
                "resolution lowered from {want} to {res}: the model is evaluated point by \
                 point ({:.3} ms a point)",
                1e3 * spp
            ));
        }
        let blob = wire::encode_mesh(&data);
        let level = Arc::new(MeshLevel {
            level: i,
            data,
            blob,
            seconds: t.elapsed().as_secs_f64(),
        });
        self.publish(gen, |c| c.meshes.push(level));
        let last = i + 1 == self.cfg.levels.len();
        self.elapsed(
            gen,
            match (i, last) {
                (0, _) => "first_mesh_s",
                (_, true) => "refined_mesh_s",
                _ => "mesh_s",
            },
        );
        true
    }

    /// Whether a mesh at `res` is already published for `gen`.
    fn already_at(&self, gen: u64, res: usize) -> bool {
        let st = lock(&self.state);
        st.cur.gen == gen && st.cur.meshes.iter().any(|m| m.data.resolution == res)
    }

    /// Analysis stage `k` (0 quick, 1 refined); false when the generation
    /// stopped.
    fn analyse(
        &self,
        gen: u64,
        shape: &Shape,
        bounds: [[f64; 3]; 2],
        res: usize,
        k: usize,
    ) -> bool {
        let label = if k == 0 { "preview" } else { "refined" };
        self.publish(gen, |c| c.stage = format!("analysing at {res}"));
        let g = self.guard(gen);
        let limit = self.cfg.memory_limit as u64;
        let r = guarded(&g, |check| {
            Ok(engine::analyze(shape, bounds, res, limit, check)?)
        });
        match r {
            Ok(v) => {
                self.publish(gen, |c| {
                    c.analysis.retain(|a| a.0 != label);
                    c.analysis.push((label, res, v));
                });
                self.elapsed(
                    gen,
                    if k == 0 {
                        "quick_analysis_s"
                    } else {
                        "refined_analysis_s"
                    },
                );
                true
            }
            Err(e) => self.fail(gen, e),
        }
    }

    /// Waits until `settle` has passed since the edit; false if a newer
    /// edit arrived meanwhile.
    fn settle(&self, gen: u64, received: Instant) -> bool {
        let until = received + self.cfg.settle;
        let mut st = lock(&self.state);
        loop {
            if self.gen.load(Ordering::SeqCst) != gen {
                return false;
            }
            let now = Instant::now();
            if now >= until {
                return true;
            }
            st = self
                .cond
                .wait_timeout(st, until - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// Runs the probe on its own thread and waits for it at most
    /// `probe_seconds` (plus slack): a model whose single evaluation takes
    /// longer is refused, and the probe thread is left to finish its point
    /// (HyperFun bounds its loops).
    fn probe(
        &self,
        gen: u64,
        shape: &Shape,
        bounds: [[f64; 3]; 2],
    ) -> Result<engine::Probe, StudioError> {
        let budget = self.cfg.probe_seconds;
        let abandon = Arc::new(AtomicBool::new(false));
        let (tx, rx) = std::sync::mpsc::channel();
        let (s, a, ctr) = (shape.clone(), abandon.clone(), self.gen.clone());
        std::thread::Builder::new()
            .name("studio-probe".into())
            .stack_size(WORKER_STACK)
            .spawn(move || {
                let stop = || a.load(Ordering::Relaxed) || ctr.load(Ordering::Relaxed) != gen;
                let r = catch_unwind(AssertUnwindSafe(|| {
                    engine::probe(&s, bounds, 7, budget, &stop)
                }));
                let _ = tx.send(r.map_err(|p| panic_message(&p)));
            })
            .map_err(|e| StudioError::Panic(format!("cannot start the probe: {e}")))?;
        let wait = Duration::from_secs_f64(budget + 0.2);
        match rx.recv_timeout(wait) {
            Ok(Ok(p)) => match p
                .errors
                .iter()
                .find(|e| e.0.starts_with("Loop did not terminate"))
            {
                // HyperFun stops a runaway loop at its iteration budget and
                // from then on fails at once: the model never terminates.
                Some(e) => Err(StudioError::Engine(engine::EngineError::Limit(format!(
                    "the model does not terminate: {} at {}:{}; nothing was meshed",
                    e.0, e.1, e.2
                )))),
                None => Ok(p),
            },
            Ok(Err(msg)) => Err(StudioError::Panic(msg)),
            Err(_) => {
                abandon.store(true, Ordering::Relaxed);
                if self.gen.load(Ordering::SeqCst) != gen {
                    return Err(StudioError::Stale);
                }
                Err(StudioError::Engine(engine::EngineError::Limit(format!(
                    "one evaluation of the model takes longer than {:.1} s (a loop that runs to \
                     HyperFun's iteration limit?); nothing was meshed",
                    wait.as_secs_f64()
                ))))
            }
        }
    }

    /// Waits until the state's version exceeds `since` (or `wait` passes)
    /// and returns the state as the page's JSON.
    pub fn state_after(&self, since: u64, wait: Duration) -> Value {
        let until = Instant::now() + wait;
        let mut st = lock(&self.state);
        st.last_seen = Instant::now();
        while st.version <= since {
            let now = Instant::now();
            if now >= until {
                break;
            }
            st = self
                .cond
                .wait_timeout(st, until - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
        st.last_seen = Instant::now();
        self.json(&st)
    }

    /// Waits until generation `gen` finished lowering (or `wait` passes)
    /// and returns the state.
    pub fn state_when_loaded(&self, gen: u64, wait: Duration) -> Value {
        let until = Instant::now() + wait;
        let mut st = lock(&self.state);
        while !(st.cur.gen == gen && st.cur.loaded) && self.gen.load(Ordering::SeqCst) == gen {
            let now = Instant::now();
            if now >= until {
                break;
            }
            st = self
                .cond
                .wait_timeout(st, until - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
        self.json(&st)
    }

    /// Waits until generation `gen` is done (or `wait` passes); true if it is.
    pub fn wait_done(&self, gen: u64, wait: Duration) -> bool {
        let until = Instant::now() + wait;
        let mut st = lock(&self.state);
        loop {
            if st.cur.gen == gen && st.cur.done {
                return true;
            }
            let now = Instant::now();
            if now >= until || self.gen.load(Ordering::SeqCst) != gen {
                return false;
            }
            st = self
                .cond
                .wait_timeout(st, until - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// The finished parts of generation `gen`, for downloads and exports.
    pub fn snapshot(&self, gen: u64) -> Result<Snapshot, StudioError> {
        let st = lock(&self.state);
        let c = &st.cur;
        if c.gen != gen {
            return Err(StudioError::Request(format!(
                "generation {gen} is gone: the model changed (now {})",
                c.gen
            )));
        }
        let (Some(m), Some(b)) = (&c.model, c.bounds) else {
            return Err(StudioError::Request(
                "the model has no geometry yet (errors, or still loading)".into(),
            ));
        };
        Ok(Snapshot {
            gen,
            shape: m.shape.clone(),
            bounds: b,
            file: c.file.clone(),
            meshes: c.meshes.clone(),
            source: c.source.clone(),
        })
    }

    /// The blob of mesh `level` of generation `gen`.
    pub fn mesh_blob(&self, gen: u64, level: usize) -> Option<Arc<MeshLevel>> {
        let st = lock(&self.state);
        (st.cur.gen == gen)
            .then(|| st.cur.meshes.iter().find(|m| m.level == level).cloned())
            .flatten()
    }

    fn json(&self, st: &State) -> Value {
        let c = &st.cur;
        let diags: Vec<Value> = c
            .diags
            .iter()
            .map(|d| {
                json!({
                    "severity": if d.error { "error" } else { "warning" },
                    "line": d.line,
                    "col": d.col,
                    "message": d.message,
                })
            })
            .collect();
        let model = c.model.as_ref().map(|m| {
            let params: Vec<Value> = m
                .params
                .iter()
                .zip(&c.params)
                .take(MAX_PARAMS)
                .enumerate()
                .map(|(k, ((name, _), p))| {
                    json!({
                        "index": k + 1,
                        "name": format!("a[{}]", k + 1),
                        "graph_name": name,
                        "value": p.value,
                        "range": p.range,
                    })
                })
                .collect();
            json!({
                "object": m.object,
                "objects": m.objects,
                "lowered": m.lowered,
                "params": params,
                "params_total": m.params.len(),
                "attributes": m.attributes,
                "bounds": c.bounds,
                "bounds_source": c.bounds_source,
            })
        });
        let meshes: Vec<Value> = c
            .meshes
            .iter()
            .map(|m| {
                let ranges: Vec<[f32; 2]> = m
                    .data
                    .attributes
                    .iter()
                    .map(|a| {
                        a.iter()
                            .filter(|v| v.is_finite())
                            .fold([f32::INFINITY, f32::NEG_INFINITY], |r, &v| {
                                [r[0].min(v), r[1].max(v)]
                            })
                    })
                    .map(|r| if r[0] <= r[1] { r } else { [0.0, 0.0] })
                    .collect();
                json!({
                    "level": m.level,
                    "resolution": m.data.resolution,
                    "vertices": m.data.vertices.len(),
                    "triangles": m.data.triangles.len(),
                    "bytes": m.blob.len(),
                    "seconds": m.seconds,
                    "note": m.data.note,
                    "attribute_ranges": ranges,
                    "url": format!("/api/mesh?session={}&gen={}&level={}", self.id, c.gen, m.level),
                })
            })
            .collect();
        let parts: Vec<Value> = c
            .parts
            .iter()
            .map(|b| {
                json!({
                    "name": b.name,
                    "source": b.spec,
                    "kind": b.part.kind,
                    "bounds": b.part.bounds,
                    "seconds": b.part.seconds,
                    "cached": b.cached,
                    "coarse_step": b.coarse,
                    "notes": b.part.notes,
                })
            })
            .collect();
        let mut analysis = serde_json::Map::new();
        for (label, res, v) in &c.analysis {
            analysis.insert(label.to_string(), json!({ "resolution": res, "report": v }));
        }
        let timings: serde_json::Map<String, Value> = c
            .timings
            .iter()
            .map(|(k, v)| (k.to_string(), json!(v)))
            .collect();
        json!({
            "session": self.id,
            "version": st.version,
            "gen": c.gen,
            "latest_gen": self.gen.load(Ordering::SeqCst),
            "file": c.file,
            "loaded": c.loaded,
            "stage": c.stage,
            "done": c.done,
            "error": c.error,
            "diagnostics": diags,
            "rendered": c.rendered,
            "warnings": c.warnings,
            "model": model,
            "parts": parts,
            "meshes": meshes,
            "analysis": analysis,
            "timings": timings,
            "levels": self.cfg.levels,
        })
    }
}

/// Proven bounds grown by 2 % of their size (and at least 1e-6) on every
/// side, so the surface is not cut by the box.
fn pad(b: [[f64; 3]; 2]) -> [[f64; 3]; 2] {
    let mut out = b;
    for a in 0..3 {
        let m = (0.02 * (b[1][a] - b[0][a])).max(1e-6);
        out[0][a] -= m;
        out[1][a] += m;
    }
    out
}

/// All sessions of a server.
pub struct Sessions {
    map: Mutex<HashMap<String, Arc<Session>>>,
    cfg: Arc<Config>,
    parts: Arc<Parts>,
}

/// Interval evaluations [`Session::part_box`] may spend before the
/// bounds search takes over.
const PART_BOX_EVALS: usize = 50_000;

/// Parameters the page gets sliders for (the rest keep their values).
pub const MAX_PARAMS: usize = 64;

/// Sessions not polled for this long are dropped when a new one starts.
const IDLE: Duration = Duration::from_secs(600);

impl Sessions {
    /// No sessions yet; data fields are read from under `root`.
    pub fn new(cfg: Config, root: PathBuf) -> Sessions {
        let parts = Arc::new(Parts::new(root, cfg.memory_limit as u64));
        Sessions {
            map: Mutex::new(HashMap::new()),
            cfg: Arc::new(cfg),
            parts,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// A new session (idle ones are dropped first).
    pub fn create(&self) -> Result<Arc<Session>, StudioError> {
        let mut map = lock(&self.map);
        map.retain(|_, s| {
            let st = lock(&s.state);
            st.worker || st.last_seen.elapsed() < IDLE
        });
        if map.len() >= self.cfg.max_sessions {
            return Err(StudioError::Request(format!(
                "too many sessions open ({}); close a tab",
                map.len()
            )));
        }
        // Random, so one session (or another local user) cannot guess
        // another's id; unique among the open ones.
        let id = loop {
            let id = format!("s{}", crate::auth::random_hex(crate::auth::SESSION_BYTES)?);
            if !map.contains_key(&id) {
                break id;
            }
        };
        let s = Arc::new(Session::new(
            id.clone(),
            self.cfg.clone(),
            self.parts.clone(),
        ));
        map.insert(id, s.clone());
        Ok(s)
    }

    /// The session `id`.
    pub fn get(&self, id: &str) -> Result<Arc<Session>, StudioError> {
        lock(&self.map).get(id).cloned().ok_or_else(|| {
            StudioError::Request(format!("unknown session '{id}' (reload the page)"))
        })
    }
}
