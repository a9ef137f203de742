//! Runs the studio until interrupted, as `microfrep serve` will:
//! `cargo run --release -p microfrep-studio --example serve -- [MODEL.hf] [--port N] [--listen ADDR] [--field NAME=FILE[:opts]]...`.

use microfrep_studio::{serve, ServeOptions};

fn main() {
    let mut opts = ServeOptions::default();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--port" => match args.next().and_then(|p| p.parse().ok()) {
                Some(p) => opts.port = p,
                None => fail("--port needs a number"),
            },
            "--listen" => match args.next().and_then(|p| p.parse().ok()) {
                Some(ip) => opts.listen = ip,
                None => fail("--listen needs an IP address"),
            },
            "--field" => match args.next().as_deref().and_then(|f| f.split_once('=')) {
                Some((name, source)) => opts.fields.push((name.into(), source.into())),
                None => fail("--field needs NAME=FILE[:opts]"),
            },
            m if !m.starts_with('-') => opts.model = Some(m.into()),
            other => fail(&format!("unknown option {other}")),
        }
    }
    if let Err(e) = serve(opts) {
        fail(&e.to_string());
    }
}

fn fail(msg: &str) -> ! {
    eprintln!("serve: {msg}");
    std::process::exit(2);
}
