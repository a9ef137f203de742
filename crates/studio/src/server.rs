//! The HTTP side: routing, request checks and replies.
//!
//! Every request runs on its own thread, with a stack sized for what a
//! request does ([`REQUEST_STACK`]). Three kinds are admitted separately,
//! so one kind cannot starve another: the page and its static assets (at
//! most [`MAX_STATIC`] at once), long polls that wait for news
//! (`/api/state`, `/api/wait`; at most [`MAX_POLLS`]) and the rest, the
//! work (at most [`MAX_IN_FLIGHT`]). Past a limit, or when no thread can be
//! started (address space under `ulimit -v`), a request is answered 503
//! with a message to retry, never dropped. A render or export whose client
//! closes the connection is stopped at its next check ([`crate::conn`]).
//!
//! Requests must name a loopback host when the server listens on loopback
//! (against DNS rebinding), carry the studio's token (header
//! `X-Studio-Token` or query `token`; the static assets and `GET /api`
//! excepted), and every `POST` must carry the header `X-Studio: 1`, which
//! a cross-site form cannot send, so other web pages and other local users
//! cannot drive the studio.

use crate::auth;
use crate::conn::Watch;
use crate::error::{io_at, StudioError};
use crate::export;
use crate::paths;
use crate::session::{panic_message, Edit, MeshLevel, Sessions};
use serde_json::{json, Value};
use std::io::Read;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tiny_http::{Header, Method, Request, Response, StatusCode};

/// Work requests (everything but the page, its assets and long polls)
/// handled at once.
pub const MAX_IN_FLIGHT: usize = 64;
/// Long polls (`/api/state`, `/api/wait`) waiting at once.
pub const MAX_POLLS: usize = 128;
/// Page and asset requests served at once.
pub const MAX_STATIC: usize = 64;
/// Stack of a request thread. Requests evaluate lowered models (the
/// meshing, slicing and rendering run on the rayon pool, and HyperFun's
/// per-point interpreter grows its stack on the heap where it nests deeply)
/// and may drop the last reference to a model's graph, which does not
/// recurse; 1 GiB stacks let only a few requests start under `ulimit -v`.
pub const REQUEST_STACK: usize = 8 << 20;
/// Largest request body accepted.
pub const MAX_BODY: u64 = 4 << 20;
/// Longest a state poll waits for news.
const POLL: Duration = Duration::from_secs(20);

const INDEX: &str = include_str!("../assets/index.html");
const STUDIO_JS: &str = include_str!("../assets/studio.js");
/// The viewer, with the camera's pure functions (`camera.js`) in front: one
/// script, not two, as tiny_http 0.12 can leave a sixth connection the
/// browser opens at once unserved while the others are kept alive (its
/// thread pool counts a woken thread as still waiting).
const VIEWER_JS: &str = concat!(
    include_str!("../assets/camera.js"),
    "\n",
    include_str!("../assets/viewer.js")
);
const EDITOR_JS: &str = include_str!("../assets/editor.js");
/// The HTTP API's reference, served at `GET /api`.
pub const API_MD: &str = include_str!("../API.md");
const CSS: &str = include_str!("../assets/studio.css");
/// The model shown when none was named.
pub const SAMPLE: &str = include_str!("../assets/sample.hf");

/// What the server shares between requests.
pub(crate) struct Shared {
    pub sessions: Sessions,
    /// Canonical working directory: the only place the page reads and writes.
    pub root: PathBuf,
    /// The model named at start: (name shown, source).
    pub initial: (String, String),
    pub addr: SocketAddr,
    /// The token every request must carry.
    pub token: String,
    /// Work requests running.
    pub in_flight: AtomicUsize,
    /// Long polls waiting.
    pub polls: AtomicUsize,
    /// Page and asset requests being served.
    pub statics: AtomicUsize,
    /// Staging folders for slice downloads.
    pub scratch: PathBuf,
    pub jobs: AtomicUsize,
}

/// A reply before it becomes a tiny_http response.
pub(crate) struct Reply {
    status: u16,
    kind: &'static str,
    body: Body,
    headers: Vec<(String, String)>,
}

enum Body {
    Bytes(Vec<u8>),
    Mesh(Arc<MeshLevel>),
}

impl Reply {
    fn bytes(kind: &'static str, body: Vec<u8>) -> Reply {
        Reply {
            status: 200,
            kind,
            body: Body::Bytes(body),
            headers: Vec::new(),
        }
    }
    fn json(v: Value) -> Reply {
        Reply::bytes("application/json", v.to_string().into_bytes())
    }
    fn text(kind: &'static str, s: &str) -> Reply {
        Reply::bytes(kind, s.as_bytes().to_vec())
    }
    fn status(mut self, s: u16) -> Reply {
        self.status = s;
        self
    }
    fn header(mut self, k: &str, v: &str) -> Reply {
        self.headers.push((k.into(), v.into()));
        self
    }
    fn attachment(self, name: &str) -> Reply {
        let safe: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "._-".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        self.header(
            "Content-Disposition",
            &format!("attachment; filename=\"{safe}\""),
        )
    }
    fn error(e: &StudioError) -> Reply {
        let r = Reply::json(json!({ "error": e.to_string() })).status(e.status());
        match e {
            StudioError::Busy(_) => r.header("Retry-After", "1"),
            _ => r,
        }
    }
}

/// A `Read` over a shared mesh blob, so large meshes are not copied.
struct BlobReader {
    m: Arc<MeshLevel>,
    at: usize,
}

impl Read for BlobReader {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let rest = &self.m.blob[self.at..];
        let n = rest.len().min(buf.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.at += n;
        Ok(n)
    }
}

fn header(k: &str, v: &str) -> Option<Header> {
    Header::from_bytes(k.as_bytes(), v.as_bytes()).ok()
}

fn send(rq: Request, r: Reply) {
    let mut headers: Vec<Header> = [
        ("Content-Type", r.kind),
        ("Cache-Control", "no-store"),
        ("X-Content-Type-Options", "nosniff"),
        ("Referrer-Policy", "no-referrer"),
    ]
    .iter()
    .filter_map(|(k, v)| header(k, v))
    .collect();
    if r.kind.starts_with("text/html") {
        headers.extend(header(
            "Content-Security-Policy",
            "default-src 'self'; img-src 'self' blob: data:; style-src 'self'; \
             script-src 'self'; connect-src 'self'; frame-ancestors 'none'",
        ));
    }
    headers.extend(r.headers.iter().filter_map(|(k, v)| header(k, v)));
    let status = StatusCode(r.status);
    // The client may have gone away; nothing to do about it then.
    let _ = match r.body {
        Body::Bytes(b) => {
            let len = b.len();
            rq.respond(Response::new(
                status,
                headers,
                std::io::Cursor::new(b),
                Some(len),
                None,
            ))
        }
        Body::Mesh(m) => {
            let len = m.blob.len();
            rq.respond(Response::new(
                status,
                headers,
                BlobReader { m, at: 0 },
                Some(len),
                None,
            ))
        }
    };
}

/// What a request is, for admission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// The page, its scripts and styles, the API document.
    Static,
    /// Waits for news: `/api/state`, `/api/wait`.
    Poll,
    /// Everything else.
    Work,
}

/// Paths served without the token: the page's scripts and styles (no
/// secret, and what a page without its token needs to say so) and the API
/// document.
const PUBLIC: &[&str] = &[
    "/studio.js",
    "/viewer.js",
    "/editor.js",
    "/studio.css",
    "/favicon.ico",
    "/api",
];

fn kind(url: &str) -> Kind {
    let path = url.split_once('?').map_or(url, |(p, _)| p);
    if PUBLIC.contains(&path) || path == "/" || path == "/index.html" {
        Kind::Static
    } else if path == "/api/state" || path == "/api/wait" {
        Kind::Poll
    } else {
        Kind::Work
    }
}

impl Shared {
    fn counter(&self, k: Kind) -> (&AtomicUsize, usize) {
        match k {
            Kind::Static => (&self.statics, MAX_STATIC),
            Kind::Poll => (&self.polls, MAX_POLLS),
            Kind::Work => (&self.in_flight, MAX_IN_FLIGHT),
        }
    }
}

/// The reply to a request that cannot be taken now.
fn busy(what: &str) -> Reply {
    Reply::json(json!({
        "error": format!("the studio is busy ({what}); retry in a moment"),
        "busy": true,
    }))
    .status(503)
    .header("Retry-After", "1")
}

/// Accepts requests until the server is unblocked.
pub(crate) fn run(server: Arc<tiny_http::Server>, shared: Arc<Shared>) {
    for rq in server.incoming_requests() {
        let k = kind(rq.url());
        let (count, max) = shared.counter(k);
        if count.fetch_add(1, Ordering::SeqCst) >= max {
            count.fetch_sub(1, Ordering::SeqCst);
            let what = match k {
                Kind::Static => format!("{max} page requests at once"),
                Kind::Poll => format!("{max} long polls at once"),
                Kind::Work => format!("{max} requests at once"),
            };
            send(rq, busy(&what));
            continue;
        }
        // The request goes back to this thread if no thread can start.
        let cell = Arc::new(Mutex::new(Some(rq)));
        let (sh, c2) = (shared.clone(), cell.clone());
        let spawned = std::thread::Builder::new()
            .name("studio-request".into())
            .stack_size(REQUEST_STACK)
            .spawn(move || {
                let rq = c2.lock().unwrap_or_else(|e| e.into_inner()).take();
                if let Some(rq) = rq {
                    handle(rq, &sh);
                }
                sh.counter(k).0.fetch_sub(1, Ordering::SeqCst);
            });
        if let Err(e) = spawned {
            count.fetch_sub(1, Ordering::SeqCst);
            let rq = cell.lock().unwrap_or_else(|e| e.into_inner()).take();
            if let Some(rq) = rq {
                send(rq, busy(&format!("cannot start a thread: {e}")));
            }
        }
    }
}

fn handle(mut rq: Request, sh: &Shared) {
    let r = catch_unwind_reply(|| route(&mut rq, sh));
    send(rq, r);
}

fn catch_unwind_reply(f: impl FnOnce() -> Result<Reply, StudioError>) -> Reply {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(Ok(r)) => r,
        Ok(Err(e)) => Reply::error(&e),
        Err(p) => Reply::error(&StudioError::Panic(panic_message(&p))),
    }
}

fn hex(c: u8) -> Option<u8> {
    (c as char).to_digit(16).map(|d| d as u8)
}

/// Percent-decodes a query component (`+` is a space).
fn decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'+' => out.push(b' '),
            b'%' if i + 2 < b.len() && hex(b[i + 1]).is_some() && hex(b[i + 2]).is_some() => {
                out.push(hex(b[i + 1]).unwrap_or(0) * 16 + hex(b[i + 2]).unwrap_or(0));
                i += 2;
            }
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

struct Query(Vec<(String, String)>);

impl Query {
    fn parse(q: &str) -> Query {
        Query(
            q.split('&')
                .filter(|p| !p.is_empty())
                .map(|p| match p.split_once('=') {
                    Some((k, v)) => (decode(k), decode(v)),
                    None => (decode(p), String::new()),
                })
                .collect(),
        )
    }
    fn get(&self, k: &str) -> Option<&str> {
        self.0.iter().find(|(n, _)| n == k).map(|(_, v)| v.as_str())
    }
    fn req(&self, k: &str) -> Result<&str, StudioError> {
        self.get(k)
            .ok_or_else(|| StudioError::Request(format!("missing query parameter '{k}'")))
    }
    fn num<T: std::str::FromStr>(&self, k: &str) -> Result<T, StudioError> {
        self.req(k)?
            .parse()
            .map_err(|_| StudioError::Request(format!("query parameter '{k}' is not a number")))
    }
    fn num_or<T: std::str::FromStr>(&self, k: &str, d: T) -> Result<T, StudioError> {
        match self.get(k) {
            Some(_) => self.num(k),
            None => Ok(d),
        }
    }
}

fn host_ok(rq: &Request, sh: &Shared) -> bool {
    if !sh.addr.ip().is_loopback() {
        return true;
    }
    let port = sh.addr.port();
    let host = rq
        .headers()
        .iter()
        .find(|h| h.field.equiv("Host"))
        .map(|h| h.value.as_str().to_ascii_lowercase());
    match host {
        Some(h) => ["127.0.0.1", "localhost", "[::1]"]
            .iter()
            .any(|n| h == format!("{n}:{port}") || (port == 80 && h == *n)),
        None => false,
    }
}

fn has_header(rq: &Request, k: &str, v: &str) -> bool {
    rq.headers()
        .iter()
        .any(|h| h.field.as_str().as_str().eq_ignore_ascii_case(k) && h.value.as_str() == v)
}

/// The request carries the studio's token, as the header `X-Studio-Token`
/// or the query parameter `token`.
fn token_ok(rq: &Request, q: &Query, sh: &Shared) -> bool {
    let header = rq
        .headers()
        .iter()
        .find(|h| h.field.equiv("X-Studio-Token"))
        .map(|h| h.value.as_str());
    header
        .or_else(|| q.get("token"))
        .is_some_and(|t| auth::same(t, &sh.token))
}

/// Watches the request's connection, so a job stops when its client goes.
fn watch(rq: &Request, sh: &Shared) -> Option<Watch> {
    Watch::new(rq.remote_addr().copied(), sh.addr.port())
}

fn body_json(rq: &mut Request) -> Result<Value, StudioError> {
    let mut s = String::new();
    rq.as_reader()
        .take(MAX_BODY + 1)
        .read_to_string(&mut s)
        .map_err(|e| StudioError::Request(format!("reading the request: {e}")))?;
    if s.len() as u64 > MAX_BODY {
        return Err(StudioError::Request(format!(
            "request body over {} MiB",
            MAX_BODY >> 20
        )));
    }
    serde_json::from_str(&s).map_err(|e| StudioError::Request(format!("request JSON: {e}")))
}

fn field<'a>(v: &'a Value, k: &str) -> Result<&'a Value, StudioError> {
    v.get(k)
        .ok_or_else(|| StudioError::Request(format!("missing field '{k}'")))
}

fn str_field<'a>(v: &'a Value, k: &str) -> Result<&'a str, StudioError> {
    field(v, k)?
        .as_str()
        .ok_or_else(|| StudioError::Request(format!("field '{k}' must be a string")))
}

fn f64_field(v: &Value, k: &str) -> Result<f64, StudioError> {
    let x = field(v, k)?
        .as_f64()
        .ok_or_else(|| StudioError::Request(format!("field '{k}' must be a number")))?;
    if !x.is_finite() {
        return Err(StudioError::Request(format!("field '{k}' must be finite")));
    }
    Ok(x)
}

/// `[[x0, y0, z0], [x1, y1, z1]]` with min < max on every axis.
fn parse_bounds(v: &Value) -> Result<[[f64; 3]; 2], StudioError> {
    let bad = || {
        StudioError::Request(
            "bounds must be [[xmin, ymin, zmin], [xmax, ymax, zmax]] with min < max".into(),
        )
    };
    let rows = v.as_array().filter(|r| r.len() == 2).ok_or_else(bad)?;
    let mut b = [[0.0; 3]; 2];
    for (i, r) in rows.iter().enumerate() {
        let r = r.as_array().filter(|r| r.len() == 3).ok_or_else(bad)?;
        for (a, x) in r.iter().enumerate() {
            b[i][a] = x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
        }
    }
    if (0..3).any(|a| b[1][a] <= b[0][a]) {
        return Err(bad());
    }
    Ok(b)
}

/// What answers one endpoint.
type Handler = fn(&mut Request, &Shared, &Query) -> Result<Reply, StudioError>;

/// One endpoint of the server: its method and path, and what answers it.
pub struct Route {
    /// `GET` or `POST`.
    pub method: &'static str,
    /// The path, without a query.
    pub path: &'static str,
    handler: Handler,
}

impl std::fmt::Debug for Route {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.method, self.path)
    }
}

const fn get(path: &'static str, handler: Handler) -> Route {
    Route {
        method: "GET",
        path,
        handler,
    }
}

const fn post(path: &'static str, handler: Handler) -> Route {
    Route {
        method: "POST",
        path,
        handler,
    }
}

/// Every endpoint the server answers, as the router looks them up; each is
/// documented in `API.md` (served at `GET /api`), which a test checks.
pub const ROUTES: &[Route] = &[
    get("/", page),
    get("/index.html", page),
    get("/studio.js", studio_js),
    get("/viewer.js", viewer_js),
    get("/editor.js", editor_js),
    get("/studio.css", css),
    get("/favicon.ico", favicon),
    get("/api", api_doc),
    post("/api/session", new_session),
    post("/api/edit", edit),
    get("/api/state", state),
    get("/api/wait", wait),
    get("/api/mesh", mesh),
    get("/api/section.png", section_png),
    get("/api/render.png", render_png),
    get("/api/export.stl", export_stl),
    get("/api/export.hf", export_hf),
    get("/api/slices.zip", slices_zip),
    post("/api/slices", slices_dir),
    post("/api/save", save),
    post("/api/fill", fill_part),
    get("/api/files", files),
    get("/api/file", file),
];

fn route(rq: &mut Request, sh: &Shared) -> Result<Reply, StudioError> {
    if !host_ok(rq, sh) {
        return Ok(Reply::text("text/plain", "unknown host").status(421));
    }
    let url = rq.url().to_string();
    let (path, query) = url.split_once('?').unwrap_or((&url, ""));
    let q = Query::parse(query);
    let method = rq.method().clone();
    if !PUBLIC.contains(&path) && !token_ok(rq, &q, sh) {
        let msg = format!(
            "missing or wrong token: open the address the studio printed when it started \
             (http://{}/?token=...); scripts send the token as the header X-Studio-Token",
            sh.addr
        );
        if method == Method::Get && (path == "/" || path == "/index.html") {
            return Ok(Reply::text("text/plain; charset=utf-8", &msg).status(403));
        }
        return Ok(Reply::json(json!({ "error": msg })).status(403));
    }
    if method == Method::Post && !has_header(rq, "X-Studio", "1") {
        return Ok(Reply::json(json!({"error": "missing header X-Studio: 1"})).status(403));
    }
    match ROUTES
        .iter()
        .find(|r| r.path == path && r.method == method.as_str())
    {
        Some(r) => (r.handler)(rq, sh, &q),
        None => Ok(
            Reply::json(json!({"error": format!("no such endpoint: {} {path}", method)}))
                .status(404),
        ),
    }
}

fn page(_: &mut Request, _: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::text("text/html; charset=utf-8", INDEX))
}

fn studio_js(_: &mut Request, _: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::text("text/javascript; charset=utf-8", STUDIO_JS))
}

fn viewer_js(_: &mut Request, _: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::text("text/javascript; charset=utf-8", VIEWER_JS))
}

fn editor_js(_: &mut Request, _: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::text("text/javascript; charset=utf-8", EDITOR_JS))
}

fn css(_: &mut Request, _: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::text("text/css; charset=utf-8", CSS))
}

fn favicon(_: &mut Request, _: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::bytes("image/x-icon", Vec::new()).status(204))
}

fn api_doc(_: &mut Request, _: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::text("text/markdown; charset=utf-8", API_MD))
}

fn new_session(_: &mut Request, sh: &Shared, _: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.create()?;
    Ok(Reply::json(json!({
        "session": s.id,
        "file": sh.initial.0,
        "source": sh.initial.1,
        "files": paths::list_models(&sh.root, 4, 500),
        "levels": sh.sessions.config().levels,
    })))
}

fn edit(rq: &mut Request, sh: &Shared, _: &Query) -> Result<Reply, StudioError> {
    let received = Instant::now();
    let v = body_json(rq)?;
    let s = sh.sessions.get(str_field(&v, "session")?)?;
    let source = str_field(&v, "source")?.to_string();
    let file = v
        .get("file")
        .and_then(Value::as_str)
        .filter(|f| !f.is_empty())
        .unwrap_or("model.hf")
        .to_string();
    let object = v
        .get("object")
        .and_then(Value::as_str)
        .filter(|o| !o.is_empty())
        .map(str::to_string);
    let params = match v.get("params") {
        None | Some(Value::Null) => None,
        Some(Value::Array(a)) => Some(
            a.iter()
                .map(|x| match x {
                    Value::Null => Ok(None),
                    x => x
                        .as_f64()
                        .filter(|x| x.is_finite())
                        .map(Some)
                        .ok_or_else(|| {
                            StudioError::Request("params must be finite numbers or null".into())
                        }),
                })
                .collect::<Result<Vec<Option<f64>>, _>>()?,
        ),
        Some(_) => return Err(StudioError::Request("params must be an array".into())),
    };
    let bounds = match v.get("bounds") {
        None | Some(Value::Null) => None,
        Some(b) => Some(parse_bounds(b)?),
    };
    let fields = match v.get("fields") {
        None | Some(Value::Null) => Vec::new(),
        Some(Value::Object(m)) => m
            .iter()
            .map(|(name, spec)| {
                let ident = name.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
                    && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
                match spec.as_str() {
                    Some(s) if ident && !s.is_empty() => Ok((name.clone(), s.to_string())),
                    _ => Err(StudioError::Request(format!(
                        "fields: '{name}' must be a name bound to a source string, e.g. \
                         {{\"part\": \"femur.stl\"}}"
                    ))),
                }
            })
            .collect::<Result<Vec<_>, _>>()?,
        Some(_) => {
            return Err(StudioError::Request(
                "fields must be an object of NAME: SOURCE".into(),
            ))
        }
    };
    let gen = s.edit(Edit {
        source,
        file,
        object,
        params,
        bounds,
        fields,
        received,
    })?;
    let wait = v
        .get("wait_ms")
        .and_then(Value::as_u64)
        .unwrap_or(1500)
        .min(5000);
    Ok(Reply::json(
        s.state_when_loaded(gen, Duration::from_millis(wait)),
    ))
}

fn state(_: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let since: u64 = q.num_or("since", 0)?;
    let wait: u64 = q.num_or("wait_ms", POLL.as_millis() as u64)?;
    Ok(Reply::json(
        s.state_after(since, Duration::from_millis(wait).min(POLL)),
    ))
}

/// Waits for a generation to finish all its stages (for scripts and tests).
fn wait(_: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let gen: u64 = q.num("gen")?;
    let wait: u64 = q.num_or("wait_ms", 60_000)?;
    let done = s.wait_done(gen, Duration::from_millis(wait.min(600_000)));
    let mut st = s.state_after(0, Duration::ZERO);
    st["finished"] = json!(done);
    Ok(Reply::json(st))
}

fn mesh(_: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let gen: u64 = q.num("gen")?;
    let level: usize = q.num("level")?;
    match s.mesh_blob(gen, level) {
        Some(m) => Ok(Reply {
            status: 200,
            kind: "application/octet-stream",
            body: Body::Mesh(m),
            headers: Vec::new(),
        }),
        None => Err(StudioError::Request(format!(
            "no mesh level {level} for generation {gen}"
        ))),
    }
}

fn section_png(rq: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let snap = s.snapshot(q.num("gen")?)?;
    let axis: usize = q.num("axis")?;
    if axis > 2 {
        return Err(StudioError::Request("axis must be 0, 1 or 2".into()));
    }
    let value: f64 = q.num("value")?;
    let (w, h): (usize, usize) = (q.num_or("w", 256)?, q.num_or("h", 256)?);
    if w > 2048 || h > 2048 {
        return Err(StudioError::Request(
            "section images are at most 2048 pixels a side".into(),
        ));
    }
    Ok(Reply::bytes(
        "image/png",
        export::section(sh, &snap, axis, value, w, h, watch(rq, sh))?,
    ))
}

fn render_png(rq: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let snap = s.snapshot(q.num("gen")?)?;
    let (w, h): (usize, usize) = (q.num_or("w", 640)?, q.num_or("h", 480)?);
    if w > 2048 || h > 2048 {
        return Err(StudioError::Request(
            "renders are at most 2048 pixels a side".into(),
        ));
    }
    let view = q.get("view").unwrap_or("iso");
    let cut = q.get("cutaway") == Some("1");
    Ok(Reply::bytes(
        "image/png",
        export::render(sh, &snap, view, cut, w, h, watch(rq, sh))?,
    ))
}

fn export_stl(rq: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let snap = s.snapshot(q.num("gen")?)?;
    let res: Option<usize> = match q.get("resolution") {
        Some(_) => Some(q.num("resolution")?),
        None => None,
    };
    let bytes = export::stl(sh, &snap, res, watch(rq, sh))?;
    Ok(Reply::bytes("model/stl", bytes).attachment(&stem_with(&snap.file, ".stl")))
}

fn export_hf(_: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let snap = s.snapshot(q.num("gen")?)?;
    Ok(Reply::text("text/plain; charset=utf-8", &snap.source)
        .attachment(&stem_with(&snap.file, ".hf")))
}

fn slices_zip(rq: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let s = sh.sessions.get(q.req("session")?)?;
    let snap = s.snapshot(q.num("gen")?)?;
    let layer: f64 = q.num("layer")?;
    let pixel: f64 = q.num("pixel")?;
    let format = export::slice_format(q.get("format").unwrap_or("png"))?;
    let bytes = export::slices_zip(sh, &snap, layer, pixel, format, watch(rq, sh))?;
    Ok(Reply::bytes("application/zip", bytes).attachment(&stem_with(&snap.file, "-slices.zip")))
}

fn slices_dir(rq: &mut Request, sh: &Shared, _: &Query) -> Result<Reply, StudioError> {
    let v = body_json(rq)?;
    let s = sh.sessions.get(str_field(&v, "session")?)?;
    let gen = field(&v, "gen")?
        .as_u64()
        .ok_or_else(|| StudioError::Request("gen must be a number".into()))?;
    let snap = s.snapshot(gen)?;
    let format = export::slice_format(v.get("format").and_then(Value::as_str).unwrap_or("png"))?;
    let dir = str_field(&v, "dir")?;
    let (written, layers) = export::slices_dir(
        sh,
        &snap,
        f64_field(&v, "layer")?,
        f64_field(&v, "pixel")?,
        format,
        dir,
        watch(rq, sh),
    )?;
    Ok(Reply::json(json!({ "written": written, "layers": layers })))
}

fn save(rq: &mut Request, sh: &Shared, _: &Query) -> Result<Reply, StudioError> {
    let v = body_json(rq)?;
    let path = str_field(&v, "path")?;
    let source = str_field(&v, "source")?;
    if !path.to_ascii_lowercase().ends_with(".hf") {
        return Err(StudioError::Path {
            path: path.into(),
            reason: "only .hf files can be saved".into(),
        });
    }
    let c = paths::writable(&sh.root, path, false)?;
    export::write_atomic(&c.full, source.as_bytes())?;
    Ok(Reply::json(json!({ "saved": c.relative })))
}

fn fill_part(rq: &mut Request, sh: &Shared, _: &Query) -> Result<Reply, StudioError> {
    let v = body_json(rq)?;
    let s = sh.sessions.get(str_field(&v, "session")?)?;
    let req = crate::fill::parse(&v)?;
    let snap = match req.part {
        crate::fill::PartSpec::Current => {
            let gen = field(&v, "gen")?
                .as_u64()
                .ok_or_else(|| StudioError::Request("gen must be a number".into()))?;
            Some(s.snapshot(gen)?)
        }
        crate::fill::PartSpec::File(_) => None,
    };
    Ok(Reply::json(export::fill(
        sh,
        &req,
        snap.as_ref(),
        watch(rq, sh),
    )?))
}

fn files(_: &mut Request, sh: &Shared, _: &Query) -> Result<Reply, StudioError> {
    Ok(Reply::json(json!({
        "files": paths::list_models(&sh.root, 4, 500)
    })))
}

fn file(_: &mut Request, sh: &Shared, q: &Query) -> Result<Reply, StudioError> {
    let path = q.req("path")?;
    if !path.to_ascii_lowercase().ends_with(".hf") {
        return Err(StudioError::Path {
            path: path.into(),
            reason: "only .hf files can be opened".into(),
        });
    }
    let c = paths::existing(&sh.root, path)?;
    let meta = std::fs::metadata(&c.full).map_err(io_at(&c.full))?;
    if !meta.is_file() || meta.len() > MAX_BODY {
        return Err(StudioError::Path {
            path: path.into(),
            reason: "not a file, or over 4 MiB".into(),
        });
    }
    let src = std::fs::read_to_string(&c.full).map_err(io_at(&c.full))?;
    Ok(Reply::text("text/plain; charset=utf-8", &src))
}

/// `name` without its `.hf` extension, plus `suffix`.
fn stem_with(name: &str, suffix: &str) -> String {
    let base = name.rsplit('/').next().unwrap_or(name);
    let stem = base
        .strip_suffix(".hf")
        .or_else(|| base.strip_suffix(".HF"))
        .unwrap_or(base);
    let stem = if stem.is_empty() { "model" } else { stem };
    format!("{stem}{suffix}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_decoding() {
        let q = Query::parse("a=1&path=sub%2Fm%20x.hf&b=%zz&c=x+y&flag");
        assert_eq!(q.get("path"), Some("sub/m x.hf"));
        assert_eq!(q.get("b"), Some("%zz"));
        assert_eq!(q.get("c"), Some("x y"));
        assert_eq!(q.get("flag"), Some(""));
        assert_eq!(q.num::<u32>("a").unwrap(), 1);
        assert!(q.num::<u32>("path").is_err());
        assert_eq!(decode("%"), "%");
        assert_eq!(decode("%4"), "%4");
        assert_eq!(stem_with("dir/toriball.hf", ".stl"), "toriball.stl");
    }
}
