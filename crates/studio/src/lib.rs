#![warn(missing_docs)]
//! microfrep studio: edit a HyperFun model in the browser and see it change.
//!
//! [`serve`] starts a local web server (loopback only unless told
//! otherwise) whose page holds an editor with the model's diagnostics
//! inline, sliders for its `a[k]` parameters, a WebGL view (orbit, zoom,
//! pan, a section plane and a cut-away that cap the cut, colouring by
//! attribute channels), the analysis figures (volume fraction, porosity,
//! surface area, components, percolation) and exports (STL, slice stacks,
//! the model). Page, scripts and styles are compiled into the binary.
//!
//! Models may call data fields by name: a comment `--field NAME=SOURCE`
//! (as `microfrep fill` writes it) or the edit's `fields` binds a mesh,
//! scan or CSV file under the working directory, built once per server and
//! kept; a model that its part bounds takes the part's box without a bounds
//! search, so a mesh part's first image comes as fast as a formula's. A
//! large scan not built yet is meshed first from a coarse stand-in (averaged
//! voxel blocks) while the full scan is built.
//!
//! Each tab is a session. An edit starts a new generation; a worker lowers
//! it, finds the box, probes the evaluation cost, then meshes it from
//! coarse to fine ([`ServeOptions::levels`]) and analyses it quickly, then
//! refined once the model has settled. A newer edit stops the older work
//! within one brick or layer. Every call into the other microfrep crates
//! lives in [`engine`], but the fill (`POST /api/fill`), which calls the
//! facade's `fill` as the CLI and Python do and answers with the filled
//! model's HyperFun source and its measured report.
//!
//! Endpoints: every route is in [`ROUTES`] (which the router itself looks
//! up) and documented in the crate's `API.md`, which the server serves at
//! `GET /api`: parameters, limits, replies and errors. Every request for
//! the page or the API carries the studio's random token
//! ([`Studio::token`], printed in the address at start as
//! `http://127.0.0.1:8321/?token=...`), every `POST` the header
//! `X-Studio: 1`; mesh buffers are laid out as [`wire`] says.
//!
//! ```
//! use microfrep_studio::{client, ServeOptions, Studio};
//! let dir = std::env::temp_dir().join(format!("mf-studio-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let studio = Studio::start(ServeOptions {
//!     port: 0,
//!     root: dir.clone(),
//!     levels: vec![16],
//!     analysis: [16, 16],
//!     ..ServeOptions::default()
//! })
//! .unwrap();
//! let c = studio.client();
//! let s = c.post_json("/api/session", &serde_json::json!({})).unwrap();
//! let id = s["session"].as_str().unwrap().to_string();
//! let src = "my_model(x[3], a[1]) { my_model = 1 - x[1]^2 - x[2]^2 - x[3]^2; }";
//! let body = serde_json::json!({"session": id, "source": src,
//!     "bounds": [[-1.1, -1.1, -1.1], [1.1, 1.1, 1.1]]});
//! let st = c.post_json("/api/edit", &body).unwrap();
//! assert_eq!(st["diagnostics"].as_array().unwrap().len(), 0);
//! studio.stop();
//! # std::fs::remove_dir_all(&dir).ok();
//! ```

mod auth;
pub mod client;
mod conn;
pub mod engine;
mod error;
mod export;
mod fill;
pub mod hints;
mod parts;
pub mod paths;
mod server;
pub mod session;
pub mod wire;

pub use error::StudioError;
pub use server::{Route, API_MD, ROUTES};

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::Duration;

/// The port [`ServeOptions::default`] listens on.
pub const DEFAULT_PORT: u16 = 8321;

/// How to run the studio.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// Address to listen on: loopback (`127.0.0.1`) unless set otherwise.
    pub listen: IpAddr,
    /// Port (0: any free port; see [`Studio::addr`]).
    pub port: u16,
    /// Working directory: the only folder the page can read and write.
    pub root: PathBuf,
    /// The model to open first (the file named on the command line).
    pub model: Option<PathBuf>,
    /// Mesh resolutions, coarse to fine (cells on the longest side).
    pub levels: Vec<usize>,
    /// Analysis resolutions: quick, refined (voxels on the longest side).
    pub analysis: [usize; 2],
    /// Time limit of one stage (a mesh level, an analysis, an export), s.
    pub job_seconds: f64,
    /// Most bytes one mesh or analysis may use (0: half the available
    /// memory, at most 4 GiB).
    pub memory_limit: f64,
    /// Quiet time after an edit before the refining stages start.
    pub settle: Duration,
    /// Most sessions (tabs) at once.
    pub max_sessions: usize,
    /// Data fields bound for every model as `(NAME, SOURCE)`, the CLI's
    /// `--field NAME=FILE[:opts]`: a mesh, scan or CSV file (relative to the
    /// working directory, or absolute; unlike the page's and the models'
    /// own bindings it may lie outside it). An edit's `fields` and a model's
    /// `--field` comments bind other names; the edit's win, then these.
    pub fields: Vec<(String, String)>,
    /// The token every request must carry (see [`Studio::token`]): `None`
    /// (the default) draws a random one of 256 bits from the OS; a fixed
    /// one (16 to 256 letters, digits, `-`, `_`) is for tests and scripts.
    pub token: Option<String>,
}

impl Default for ServeOptions {
    fn default() -> Self {
        ServeOptions {
            listen: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: DEFAULT_PORT,
            root: PathBuf::from("."),
            model: None,
            levels: vec![48, 128, 192],
            analysis: [64, 128],
            job_seconds: 60.0,
            memory_limit: 0.0,
            settle: Duration::from_millis(300),
            max_sessions: 32,
            fields: Vec::new(),
            token: None,
        }
    }
}

/// A running studio server.
pub struct Studio {
    server: Arc<tiny_http::Server>,
    addr: SocketAddr,
    thread: Option<std::thread::JoinHandle<()>>,
    scratch: PathBuf,
    token: String,
}

impl Studio {
    /// Starts listening and serving on a background thread.
    pub fn start(opts: ServeOptions) -> Result<Studio, StudioError> {
        let token = match &opts.token {
            Some(t) => {
                auth::check_token(t)?;
                t.clone()
            }
            None => auth::random_hex(auth::TOKEN_BYTES)?,
        };
        let root = opts.root.canonicalize().map_err(error::io_at(&opts.root))?;
        let initial = match &opts.model {
            Some(p) => {
                let src = std::fs::read_to_string(p).map_err(error::io_at(p))?;
                let name = p
                    .strip_prefix(&opts.root)
                    .unwrap_or(p)
                    .to_string_lossy()
                    .into_owned();
                (name, src)
            }
            None => ("sample.hf".to_string(), server::SAMPLE.to_string()),
        };
        let levels: Vec<usize> = opts.levels.iter().map(|&l| l.clamp(8, 1024)).collect();
        if levels.is_empty() {
            return Err(StudioError::Request(
                "at least one mesh level is needed".into(),
            ));
        }
        let memory_limit = if opts.memory_limit > 0.0 {
            opts.memory_limit
        } else {
            let avail = engine::memory_available().unwrap_or(4.0 * GIB);
            (0.5 * avail).min(4.0 * GIB)
        };
        let cfg = session::Config {
            levels,
            analysis: opts.analysis.map(|a| a.clamp(8, 1024)),
            job_seconds: opts.job_seconds.max(0.1),
            memory_limit,
            settle: opts.settle,
            probe_seconds: 0.25,
            max_sessions: opts.max_sessions.max(1),
            fields: opts.fields.clone(),
        };
        let want = SocketAddr::new(opts.listen, opts.port);
        let server = tiny_http::Server::http(want).map_err(|source| StudioError::Listen {
            addr: want.to_string(),
            source,
        })?;
        let addr = server
            .server_addr()
            .to_ip()
            .ok_or_else(|| StudioError::Listen {
                addr: want.to_string(),
                source: "not an IP listener".into(),
            })?;
        let scratch = std::env::temp_dir().join(format!(
            "microfrep-studio-{}-{}",
            std::process::id(),
            addr.port()
        ));
        std::fs::create_dir_all(&scratch).map_err(error::io_at(&scratch))?;
        let shared = Arc::new(server::Shared {
            sessions: session::Sessions::new(cfg, root.clone()),
            root,
            initial,
            addr,
            token: token.clone(),
            in_flight: AtomicUsize::new(0),
            polls: AtomicUsize::new(0),
            statics: AtomicUsize::new(0),
            scratch: scratch.clone(),
            jobs: AtomicUsize::new(0),
        });
        let server = Arc::new(server);
        let s2 = server.clone();
        let thread = std::thread::Builder::new()
            .name("studio-accept".into())
            .spawn(move || server::run(s2, shared))
            .map_err(|e| StudioError::Panic(format!("cannot start the server thread: {e}")))?;
        Ok(Studio {
            server,
            addr,
            thread: Some(thread),
            scratch,
            token,
        })
    }

    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's address with its token, e.g.
    /// `http://127.0.0.1:8321/?token=...`: what to open in the browser.
    pub fn url(&self) -> String {
        format!("http://{}/?token={}", self.addr, self.token)
    }

    /// The token every request must carry: as the header `X-Studio-Token`,
    /// or the query parameter `token`.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// A client of this studio that sends its token.
    pub fn client(&self) -> client::Client {
        client::Client::new(self.addr).with_token(&self.token)
    }

    /// Serves until the process ends.
    pub fn wait(mut self) {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }

    /// Stops accepting requests (requests in progress finish on their own).
    pub fn stop(mut self) {
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Studio {
    fn drop(&mut self) {
        self.server.unblock();
        let _ = std::fs::remove_dir_all(&self.scratch);
    }
}

const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

/// Runs the studio: prints its address and serves until the process ends.
pub fn serve(opts: ServeOptions) -> Result<(), StudioError> {
    let studio = Studio::start(opts)?;
    println!("microfrep studio: {}", studio.url());
    println!("(open this address; the token in it keeps other users of this machine out)");
    studio.wait();
    Ok(())
}
