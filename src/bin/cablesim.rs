//! `cablesim`: runs scenario files (shared/SCENARIO.md, docs/scenario.md).
//!
//! ```text
//! cablesim run FILE [--out DIR] [--plot] [--quiet] [--threads N]
//! cablesim check FILE
//! cablesim view FILE [--headless FRAMES] [--screenshot FILE.png]
//! ```
//! Exit status: 0 success, 2 invalid file (message with file:line:col),
//! 3 the simulation diverged (the rows computed so far are still written;
//! `view --headless`: a cable diverged), 4 the output folder or its files
//! cannot be created or written. Usage errors are clap's (2), and so is
//! `view` in a `cablesim` built without the feature `demo` (the message
//! says how to build it).
//!
//! `view` (feature `demo`, `bevy_rapier_cable::viewer`) opens the scenario
//! in a window, stepped by the Bevy plugin as `run` steps it; `--headless
//! N` runs N frames without a window and prints the time, the largest
//! tension and the probes.
//!
//! `run` steps independent cables at once on up to `--threads` threads
//! (default: the machine's cores; `World::set_threads`); the results are
//! the same bits whatever the count.
//!
//! `run` writes `results.csv` row by row as the run goes (an interrupted
//! run keeps its rows), and first removes the `results.csv`,
//! `summary.json` and `plot.png` of an earlier run in the same folder.

use bevy_rapier_cable::output::Recorder;
use bevy_rapier_cable::scenario;
use bevy_rapier_cable::sim::{SimError, World};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "cablesim",
    version,
    about = "Run wire-rope scenario files (bevy_rapier_cable)",
    after_help = "Exit status: 0 success, 2 invalid scenario file, 3 the simulation diverged (rows so far written), 4 output folder or files cannot be written."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scenario headless and write results.csv and summary.json.
    Run {
        /// Scenario file (TOML).
        file: PathBuf,
        /// Output directory (default: `out/<file stem>`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also write plot.png (one panel per probe).
        #[arg(long)]
        plot: bool,
        /// No progress bar and no summary paragraph.
        #[arg(long)]
        quiet: bool,
        /// Most threads for the cables' solves (independent cables step
        /// at once; the results are the same bits). Default: the
        /// machine's cores.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
        threads: Option<u32>,
    },
    /// Parse and validate a scenario file only.
    Check {
        /// Scenario file (TOML).
        file: PathBuf,
    },
    /// Open a scenario in an interactive window (needs the feature `demo`).
    View {
        /// Scenario file (TOML).
        file: PathBuf,
        /// Run FRAMES frames of `dt` without a window, print the time, the
        /// largest tension and the probes, and exit.
        #[arg(long, value_name = "FRAMES")]
        headless: Option<u64>,
        /// Save a PNG of the window after 1.5 s of simulated time and exit.
        #[arg(long, value_name = "FILE.png")]
        screenshot: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check { file } => match load(&file) {
            Ok((_, world)) => {
                println!(
                    "{}: ok ({} cables, {} bodies, {} probes)",
                    file.display(),
                    world.cable_names().len(),
                    world.scenario.bodies.len(),
                    world.scenario.probes.len()
                );
                ExitCode::SUCCESS
            }
            Err(code) => code,
        },
        Command::View { file, headless, screenshot } => view(&file, headless, screenshot),
        Command::Run { file, out, plot, quiet, threads } => {
            let threads = threads.map_or_else(|| std::thread::available_parallelism().map_or(1, usize::from), |n| n as usize);
            run(&file, out, plot, quiet, threads)
        }
    }
}

/// Exit status when the output folder or its files cannot be created or
/// written (0: done, 2: invalid scenario, 3: diverged, rows kept).
const EXIT_OUTPUT: u8 = 4;

/// Loads and builds a scenario; on failure prints the error and returns exit status 2.
fn load(file: &Path) -> Result<(scenario::Scenario, World), ExitCode> {
    let sc = scenario::load(file).map_err(|e| {
        eprintln!("{e}");
        ExitCode::from(2)
    })?;
    let world = World::new(sc.clone()).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(if matches!(e, SimError::Diverged { .. } | SimError::Static { .. } | SimError::BodyDiverged { .. }) { 3 } else { 2 })
    })?;
    for w in &world.warnings {
        eprintln!("warning: {w}");
    }
    Ok((sc, world))
}

fn run(file: &Path, out: Option<PathBuf>, plot: bool, quiet: bool, threads: usize) -> ExitCode {
    let (sc, mut world) = match load(file) {
        Ok(x) => x,
        Err(code) => return code,
    };
    world.set_threads(threads);
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scenario".into());
    let dir = out.unwrap_or_else(|| PathBuf::from("out").join(stem));
    if let Err(e) = std::fs::create_dir_all(&dir) {
        eprintln!("error: cannot create {}: {e}", dir.display());
        return ExitCode::from(EXIT_OUTPUT);
    }
    // Files of an earlier run would be mistaken for this one's (a plot
    // left from a run with --plot, a summary of a longer run).
    for name in ["results.csv", "summary.json", "plot.png"] {
        match std::fs::remove_file(dir.join(name)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                eprintln!("error: cannot remove the earlier {}: {e}", dir.join(name).display());
                return ExitCode::from(EXIT_OUTPUT);
            }
            _ => {}
        }
    }
    let sim = &sc.simulation;
    let frames = (sim.duration / sim.dt - 1e-9).ceil().max(0.0) as u64;
    let every = ((sim.output_interval / sim.dt).round() as u64).max(1);
    let mut rec = Recorder::new(sc.columns());
    let mut row = Vec::new();
    let bar = progress_bar(frames, quiet);
    let started = Instant::now();
    // results.csv is written as rows are made: an interrupted run keeps them.
    let mut csv = match rec.stream_csv(&dir.join("results.csv")) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_OUTPUT);
        }
    };
    let mut record = |rec: &mut Recorder, t: f64, row: &[f64]| rec.push_row(t, row).and_then(|()| csv.append(t, row));
    world.sample(&mut row);
    let mut failure = None;
    if let Err(e) = record(&mut rec, 0.0, &row) {
        eprintln!("error: {e}");
        return ExitCode::from(EXIT_OUTPUT);
    }
    for k in 1..=frames {
        if let Err(e) = world.step() {
            failure = Some(e);
            break;
        }
        if k % every == 0 || k == frames {
            world.sample(&mut row);
            if let Err(e) = record(&mut rec, world.time, &row) {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_OUTPUT);
            }
        }
        if let Some(b) = &bar {
            b.set_position(k);
        }
    }
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let wall = started.elapsed().as_secs_f64();
    let written = write_outputs(&rec, &dir, plot, world.steps, world.time, wall);
    if let Err(e) = &written {
        eprintln!("error: {e}");
    }
    if let Some(e) = failure {
        eprintln!("error: simulation stopped: {e}\n       {} rows up to t = {} s written to {}", rec.len(), world.time, dir.display());
        return ExitCode::from(3);
    }
    if written.is_err() {
        return ExitCode::from(EXIT_OUTPUT);
    }
    if !quiet {
        let (newton, _) = world.work();
        let rtf = world.time / wall.max(1e-12);
        println!(
            "{}: simulated {:.3} s in {} frames of {} s ({} cable sub-step{} each, {}) in {:.3} s wall time: {:.1}× real time, {:.2} Newton iterations per cable step. Wrote {} rows of {} columns to {}{}.",
            file.display(),
            world.time,
            world.steps,
            sim.dt,
            world.substeps,
            if world.substeps == 1 { "" } else { "s" },
            sim.integrator.name,
            wall,
            rtf,
            newton as f64 / (world.steps.max(1) * world.substeps as u64 * world.cable_names().len().max(1) as u64) as f64,
            rec.len(),
            rec.columns().len() + 1,
            dir.join("results.csv").display(),
            if plot { format!(", plot in {}", dir.join("plot.png").display()) } else { String::new() }
        );
    }
    ExitCode::SUCCESS
}

/// `cablesim view`: the file checked as `run` checks it (same messages and
/// exit status), then the viewer.
#[cfg(feature = "demo")]
fn view(file: &Path, headless: Option<u64>, screenshot: Option<PathBuf>) -> ExitCode {
    let (sc, _) = match load(file) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let options = bevy_rapier_cable::demo_support::DemoOptions { headless, screenshot, ..Default::default() };
    ExitCode::from(bevy_rapier_cable::viewer::run(sc, options))
}

/// `cablesim view` without the viewer built in: exit status 2 (usage).
#[cfg(not(feature = "demo"))]
fn view(file: &Path, _headless: Option<u64>, _screenshot: Option<PathBuf>) -> ExitCode {
    eprintln!(
        "error: `cablesim view {}`: this cablesim was built without the viewer (feature `demo`); build and run it with\n       cargo run --release --features demo -- view {}",
        file.display(),
        file.display()
    );
    ExitCode::from(2)
}

fn write_outputs(rec: &Recorder, dir: &Path, plot: bool, steps: u64, simulated: f64, wall: f64) -> Result<(), bevy_rapier_cable::output::OutputError> {
    rec.write_summary(&dir.join("summary.json"), steps, simulated, wall)?;
    if plot {
        rec.write_plot(&dir.join("plot.png"), &rec.default_panels())?;
    }
    Ok(())
}

fn progress_bar(frames: u64, quiet: bool) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if quiet || !std::io::stdout().is_terminal() {
        return None;
    }
    let b = indicatif::ProgressBar::new(frames);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} frames {elapsed_precise} ETA {eta}") {
        b.set_style(style);
    }
    Some(b)
}
