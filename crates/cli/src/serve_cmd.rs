//! `microfrep serve`: the studio, a live editor and viewer in the browser.

use anyhow::{Context, Result};
use clap::Args;
use std::net::IpAddr;
use std::path::PathBuf;

#[derive(Args)]
pub struct ServeArgs {
    /// A HyperFun model to open first (the studio edits .hf files under the
    /// working directory).
    model: Option<PathBuf>,
    /// Port on the listening address.
    #[arg(long, default_value_t = 8321)]
    port: u16,
    /// Address to listen on; only 127.0.0.1 (this machine) unless given.
    #[arg(long, default_value = "127.0.0.1")]
    listen: IpAddr,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// A mesh, scan or CSV bound as the HyperFun function NAME(x) in every
    /// model the studio opens: NAME=FILE[:key=value,...] (repeatable; a
    /// model's own `--field` comment or the page's binding wins).
    #[arg(long = "field", value_parser = crate::common::parse_field)]
    fields: Vec<(String, String)>,
}

pub fn run(a: ServeArgs) -> Result<()> {
    if let Some(n) = a.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.clamp(1, 1024))
            .build_global()
            .context("setting up the thread pool")?;
    }
    let opts = microfrep_studio::ServeOptions {
        listen: a.listen,
        port: a.port,
        model: a.model,
        root: ".".into(),
        fields: a.fields,
        ..Default::default()
    };
    microfrep_studio::serve(opts)?;
    Ok(())
}
