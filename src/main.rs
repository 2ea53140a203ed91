//! The `vrao` command line: parses and dispatches to `src/cli/`, one file per subcommand.

mod cli;

use clap::{CommandFactory, Parser, Subcommand};
use cli::choice;
use std::process::ExitCode;
use vrao_render::BackendChoice;

#[derive(Parser)]
#[command(name = "vrao", version, about = "Stereo VR ambient-occlusion renderer (SSAO, HBAO, GTAO, SSDO) on wgpu")]
struct Cli {
    /// Graphics backend: auto (a real GPU if present, else lavapipe), vulkan or gl.
    #[arg(value_parser = choice::<BackendChoice>(), long, global = true, default_value = "auto", hide_possible_values = true)]
    backend: BackendChoice,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Print the adapter, its driver, multiview and timestamp support, and key limits.
    Info,
    /// Render both eyes of a scene to left.png and right.png.
    Render(cli::render::RenderArgs),
    /// Sweep technique × samples × radius × resolution: median ms per eye per pass and
    /// error against the reference tracer; writes CSV, JSON, Markdown and a PNG plot.
    Bench(cli::bench::BenchArgs),
    /// Run a headset session: OpenXR when a runtime is present, otherwise the simulated
    /// headset; with a desktop window for --display mirror or single-pass.
    Run(cli::run::RunArgs),
    /// Reprojection quality: warp a frame to moved head poses (rotations 1–10°,
    /// translations 1–10 cm) in both modes and compare with fresh renders.
    Reprojection(cli::reprojection::ReprojectionArgs),
    /// Temporal accumulation: AO error against the reference after 1, 2, 4, 8 and 16
    /// frames (static head and yaw sweep) next to spatial-only settings.
    Temporal(cli::temporal::TemporalArgs),
    /// Headless per-eye budget test: per-pass medians against the frame budget; exit 0
    /// within budget, 3 over it.
    Budget(cli::budget::BudgetArgs),
    /// The peer: Bevy 0.19's SSAO (peers/bevy) and vrao's GTAO on the same frames, both
    /// eyes, scored by the same reference and timed in one run; a table and a plot.
    Peer(cli::peer::PeerArgs),
    /// The GPU table: per-pass ms per eye of every technique × preset × AO resolution ×
    /// foveation and the stereo frame against the budget, per scene, in one Markdown file.
    Table(cli::table::TableArgs),
}

/// The library tells the user what it does (which headset, the bench's progress) at the
/// info level and warns at the warn level: both go to stderr, vrao's own info lines as
/// plain text, everything else with its level and source. `RUST_LOG` overrides the filter.
fn init_log() {
    use std::io::Write;
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,vrao=info"))
        .format(|out, record| {
            if record.level() == log::Level::Info && record.target().starts_with("vrao") {
                writeln!(out, "{}", record.args())
            } else {
                writeln!(out, "[{} {}] {}", record.level(), record.target(), record.args())
            }
        })
        .init();
}

fn main() -> ExitCode {
    // Mesa's Vulkan drivers probe for a Wayland display and print "error: XDG_RUNTIME_DIR
    // is invalid" on headless machines although nothing is wrong; give the probe a
    // directory to look in (it then finds no display, quietly).
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    init_log();
    // clap's own usage errors print themselves and exit 2.
    let cli = Cli::parse();
    let backend = cli.backend;
    let result = match cli.command {
        Some(Command::Info) => cli::info::run(backend),
        Some(Command::Render(args)) => cli::render::run(backend, args),
        Some(Command::Bench(args)) => cli::bench::run(backend, args),
        Some(Command::Budget(args)) => cli::budget::run(backend, args),
        Some(Command::Peer(args)) => cli::peer::run(backend, args),
        Some(Command::Table(args)) => cli::table::run(backend, args),
        Some(Command::Run(args)) => cli::run::run(backend, args),
        Some(Command::Temporal(args)) => cli::temporal::run(backend, args),
        Some(Command::Reprojection(args)) => cli::reprojection::run(backend, args),
        None => {
            let _ = Cli::command().print_help();
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // Input errors (bad options, files, unwritable outputs, no device) exit 2, a
        // budget overrun 3, a GPU failure 1.
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
