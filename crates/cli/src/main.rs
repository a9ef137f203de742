//! `microfrep`: a thin shell over the library crates. Argument parsing,
//! model loading and printing only; the algorithms live in the crates.

mod eval_cmd;
mod model;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "microfrep",
    version,
    about = "Function-based microstructures: model, check, mesh, slice"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// List the built-in example models, or describe one.
    Examples {
        /// Show only this example.
        name: Option<String>,
    },
    /// Evaluate a model at points given as arguments (x y z ...) or on stdin.
    Eval(eval_cmd::EvalArgs),
}

fn main() {
    let cli = Cli::parse();
    let res = match cli.cmd {
        Cmd::Examples { name } => model::list_examples(name.as_deref()),
        Cmd::Eval(a) => eval_cmd::run(a),
    };
    if let Err(e) = res {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
