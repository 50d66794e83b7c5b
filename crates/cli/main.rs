//! The `bodyseg` binary: parses the command line, sets up logging, calls
//! bodyseg-pipeline, prints per-stage summaries and errors.
//!
//! Exit status: 0 on success, 1 on any error (printed as one `error: ...` line on
//! stderr), 2 for a command line clap rejects, 3 when a batch command (run, convert)
//! skipped frames that failed (each printed as an `error: frame ...` line).

mod args;

use anyhow::Result;
use args::{
    CalibrateCommand, Cli, Command, EvalArgs, ImportCommand, ParseArgs, ProjectArgs, RefineArgs,
    RigCommand, SynthArgs,
};
use bodyseg_pipeline::{
    Stage, calibrate_intrinsics, calibrate_stereo, calibrate_world, check_output_file,
    describe_rig, eval_files, import_rig, merge_reports, parse_file, project_file, read_rig,
    refine_file, render_report, synth_recording, write_text,
};
use clap::Parser;
use std::io::Write;
use std::process::ExitCode;
use std::time::Instant;

/// mimalloc: the refinement allocates and frees multi-megabyte arrays per person and per
/// frame; glibc hands them back to the kernel and pays page faults again on every frame
/// (measured: whole refinement of a 100k-point person 23 ms with glibc, 19 ms with
/// mimalloc, `crates/refine/examples/dbscan_cloud.rs`).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    bodyseg_pipeline::keep_freed_memory();
    let cli = Cli::parse();
    init_logging(cli.verbose);
    handle_signals();
    match run(&cli) {
        Ok(Outcome::Done) => ExitCode::SUCCESS,
        Ok(Outcome::SomeFramesFailed) => ExitCode::from(3),
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// SIGINT and SIGTERM: remove the temporary files of the writes in flight (and the
/// output folder's lock) and exit 130 or 143 (128 + the signal) with one `error:` line. A
/// batch is resumed by running the command again: finished frames are kept.
fn handle_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            bodyseg_io::remove_temporaries();
            let name = if signal == SIGINT {
                "SIGINT"
            } else {
                "SIGTERM"
            };
            eprintln!(
                "error: interrupted ({name}): temporary files removed; what was finished is kept (run the command again to resume a batch)"
            );
            std::process::exit(128 + signal);
        }
    });
}

/// Logs go to stderr. `-v` flags pick the level; without them RUST_LOG does, else `warn`.
fn init_logging(verbose: u8) {
    use tracing_subscriber::EnvFilter;
    let filter = match verbose {
        0 => EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("warn")),
        1 => EnvFilter::new("info"),
        2 => EnvFilter::new("debug"),
        _ => EnvFilter::new("trace"),
    };
    // Fails only when a subscriber is already set, which cannot happen here.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .event_format(OneLine)
        .try_init();
}

/// Log events as one line each, `warning: <message> <fields>` (`error:`, `info:`,
/// `debug:`, `trace:` for the other levels), like the binary's own `error:` lines. Warnings
/// are shown with `--quiet` too (it silences the stage lines only).
struct OneLine;

impl<S, N> tracing_subscriber::fmt::FormatEvent<S, N> for OneLine
where
    S: tracing::Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>,
    N: for<'a> tracing_subscriber::fmt::FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &tracing_subscriber::fmt::FmtContext<'_, S, N>,
        mut writer: tracing_subscriber::fmt::format::Writer<'_>,
        event: &tracing::Event<'_>,
    ) -> std::fmt::Result {
        let level = match *event.metadata().level() {
            tracing::Level::ERROR => "error",
            tracing::Level::WARN => "warning",
            tracing::Level::INFO => "info",
            tracing::Level::DEBUG => "debug",
            tracing::Level::TRACE => "trace",
        };
        write!(writer, "{level}: ")?;
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}

/// How a command that did its job ended.
enum Outcome {
    /// Everything was written.
    Done,
    /// A batch command skipped frames that failed (exit status 3).
    SomeFramesFailed,
}

fn run(cli: &Cli) -> Result<Outcome> {
    let mut outcome = Outcome::Done;
    let stages = match &cli.command {
        Command::Synth(args) => synth(args, cli.quiet)?,
        Command::Parse(args) => parse(args)?,
        Command::Project(args) => project(args)?,
        Command::Boxes(args) => boxes(args)?,
        Command::Refine(args) => refine(args)?,
        Command::Eval(args) => eval(args)?,
        Command::Rig(cmd) => rig(cmd)?,
        Command::Import(ImportCommand::Ros2(args)) => {
            let (stages, failed) = import_ros2(args, cli.quiet)?;
            if failed {
                outcome = Outcome::SomeFramesFailed;
            }
            stages
        }
        Command::Import(ImportCommand::Cloud(args)) => import_cloud(args)?,
        Command::Run(args) => {
            let (stages, failed) = run_recording_command(args, cli.quiet)?;
            if failed {
                outcome = Outcome::SomeFramesFailed;
            }
            stages
        }
        Command::Convert(args) => {
            let (stages, failed) = convert(args, cli.quiet)?;
            if failed {
                outcome = Outcome::SomeFramesFailed;
            }
            stages
        }
        Command::Calibrate(cmd) => calibrate(cmd, cli.quiet)?,
        Command::Version(args) => version(args, cli.verbose)?,
        Command::View(args) => {
            let summary = bodyseg_pipeline::view_run(&args.options())?;
            print_stdout(&format!(
                "rerun: {} ({} frames)\n",
                summary.written.display(),
                summary.frames
            ))?;
            summary.stages
        }
    };
    if !cli.quiet {
        for s in stages {
            // One write per line: stdout (the table) may be interleaved with it.
            let _ = std::io::stderr().write_all(format!("{s}\n").as_bytes());
        }
    }
    Ok(outcome)
}

/// A progress bar on stderr (frames, frames per second, time left) when stderr is a
/// terminal and not --quiet; hidden otherwise.
fn progress_bar(quiet: bool, what: &str) -> indicatif::ProgressBar {
    if quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(0);
    let style = indicatif::ProgressStyle::with_template(&format!(
        "{what} {{bar:30}} {{pos}}/{{len}} frames  {{per_sec}}  eta {{eta}}  {{msg}}"
    ))
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    bar.set_style(style);
    bar
}

/// Updates `bar` from the batch's progress.
fn show_progress(bar: &indicatif::ProgressBar, p: bodyseg_pipeline::BatchProgress) {
    bar.set_length(p.total as u64);
    bar.set_position(p.finished as u64);
    if p.failed > 0 || p.skipped > 0 {
        bar.set_message(format!("{} skipped, {} failed", p.skipped, p.failed));
    }
}

/// Prints the failed frames, one line each, on stderr.
fn print_failures(failed: &[bodyseg_pipeline::FrameFailure]) {
    for f in failed {
        eprintln!("error: frame {}: {}", f.frame, f.error);
    }
    if !failed.is_empty() {
        let n = failed.len();
        eprintln!(
            "error: {n} frame{} failed (skipped; the others were written)",
            if n == 1 { "" } else { "s" }
        );
    }
}

fn run_recording_command(args: &args::RunArgs, quiet: bool) -> Result<(Vec<Stage>, bool)> {
    let options = args.options()?;
    let bar = progress_bar(quiet, "run");
    let summary = bodyseg_pipeline::run_recording(&options, &|p| show_progress(&bar, p))?;
    bar.finish_and_clear();
    if let Some(report) = &summary.report {
        print_stdout(&report.to_markdown())?;
    }
    for f in &summary.figures {
        print_stdout(&format!("figure: {}\n", f.display()))?;
    }
    print_failures(&summary.outcome.failed);
    Ok((summary.stages, !summary.outcome.failed.is_empty()))
}

fn convert(args: &args::ConvertArgs, quiet: bool) -> Result<(Vec<Stage>, bool)> {
    let options = args.options()?;
    let bar = progress_bar(quiet, "convert");
    let summary = bodyseg_pipeline::convert_dataset(&options, &|p| show_progress(&bar, p))?;
    bar.finish_and_clear();
    print_failures(&summary.outcome.failed);
    Ok((summary.stages, !summary.outcome.failed.is_empty()))
}

fn import_ros2(args: &args::ImportRos2Args, quiet: bool) -> Result<(Vec<Stage>, bool)> {
    let bar = progress_bar(quiet, "import");
    let summary = bodyseg_pipeline::import_ros2(&args.options(), &|p| show_progress(&bar, p))?;
    bar.finish_and_clear();
    if !quiet {
        for line in &summary.cameras {
            eprintln!("{line}");
        }
    }
    for note in &summary.notes {
        eprintln!("note: {note}");
    }
    print_failures(&summary.failed);
    Ok((summary.stages, !summary.failed.is_empty()))
}

fn synth(args: &SynthArgs, quiet: bool) -> Result<Vec<Stage>> {
    let options = args.options();
    let total = options.frames;
    let start = Instant::now();
    let show = !quiet && std::io::IsTerminal::is_terminal(&std::io::stderr());
    let progress = |done: usize| {
        if show {
            let fps = done as f64 / start.elapsed().as_secs_f64().max(1e-9);
            eprint!("\rsynth: {done}/{total} frames ({fps:.1} frames/s)");
            if done == total {
                eprintln!();
            }
        }
    };
    let summary = synth_recording(&options, &progress)?;
    Ok(summary.stages)
}

fn parse(args: &ParseArgs) -> Result<Vec<Stage>> {
    let summary = parse_file(&args.options()?)?;
    Ok(summary.stages)
}

fn project(args: &ProjectArgs) -> Result<Vec<Stage>> {
    let summary = project_file(&args.options()?)?;
    Ok(summary.stages)
}

fn boxes(args: &args::BoxesArgs) -> Result<Vec<Stage>> {
    let summary = bodyseg_pipeline::boxes_file(&args.options()?)?;
    for note in &summary.notes {
        eprintln!("note: {note}");
    }
    Ok(summary.stages)
}

fn import_cloud(args: &args::ImportCloudArgs) -> Result<Vec<Stage>> {
    let summary = bodyseg_pipeline::import_cloud(&args.options())?;
    for note in &summary.notes {
        eprintln!("note: {note}");
    }
    Ok(summary.stages)
}

fn refine(args: &RefineArgs) -> Result<Vec<Stage>> {
    let summary = refine_file(&args.options()?)?;
    Ok(summary.stages)
}

fn eval(args: &EvalArgs) -> Result<Vec<Stage>> {
    if let Some(out) = &args.out {
        let mut inputs: Vec<(&str, &std::path::Path)> = args
            .merge
            .iter()
            .map(|p| ("--merge", p.as_path()))
            .collect();
        let options = args.merge.is_empty().then(|| args.options()).transpose()?;
        if let Some(o) = &options {
            inputs.push(("--gt", &o.gt));
            inputs.extend(o.predictions.iter().map(|p| ("--pred", p.path.as_path())));
        }
        check_output_file(out, &["md", "json", "txt"], &inputs)?;
    }
    let (report, mut stages) = if args.merge.is_empty() {
        let summary = eval_files(&args.options()?)?;
        (summary.report, summary.stages)
    } else {
        let start = Instant::now();
        let report = merge_reports(&args.merge)?;
        let detail = format!(
            "{} reports, configurations: {}",
            args.merge.len(),
            report.names().join(", ")
        );
        (report, vec![Stage::new("merge", start.elapsed(), detail)])
    };
    let text = render_report(&report, args.format.into())?;
    match &args.out {
        Some(path) => {
            let start = Instant::now();
            write_text(path, &text)?;
            stages.push(Stage::new(
                "write",
                start.elapsed(),
                path.display().to_string(),
            ));
        }
        None => print_stdout(&text)?,
    }
    Ok(stages)
}

fn rig(cmd: &RigCommand) -> Result<Vec<Stage>> {
    match cmd {
        RigCommand::Import(args) => {
            let summary = import_rig(&args.options()?)?;
            for note in &summary.notes {
                eprintln!("note: {note}");
            }
            Ok(summary.stages)
        }
        RigCommand::Show(args) => {
            let start = Instant::now();
            let rig = read_rig(&args.rig)?;
            let read = Stage::new("read", start.elapsed(), args.rig.display().to_string());
            print_stdout(&describe_rig(&rig))?;
            Ok(vec![read])
        }
    }
}

fn calibrate(cmd: &CalibrateCommand, quiet: bool) -> Result<Vec<Stage>> {
    let summary = match cmd {
        CalibrateCommand::Intrinsics(args) => calibrate_intrinsics(&args.options()?)?,
        CalibrateCommand::Stereo(args) => calibrate_stereo(&args.options()?)?,
        CalibrateCommand::World(args) => calibrate_world(&args.options()?)?,
    };
    // Skipped views are always reported; the per-view errors unless --quiet.
    for note in &summary.notes {
        eprintln!("note: {note}");
    }
    if !quiet {
        eprintln!("reprojection error (RMS, px):");
        for view in summary.views.iter().filter(|v| v.rms_px.is_some()) {
            if let Some(e) = view.rms_px {
                eprintln!("  {e:>7.4}  {}", view.file.display());
            }
        }
        eprintln!("  {:>7.4}  all", summary.rms_px);
    }
    Ok(summary.stages)
}

/// `bodyseg version [-v]`: the version; with -v the parser's files and where they were
/// found (nothing is loaded).
fn version(args: &args::VersionArgs, verbose: u8) -> Result<Vec<Stage>> {
    let mut text = format!("bodyseg {}\n", env!("CARGO_PKG_VERSION"));
    if verbose > 0 {
        let config = args.config.load()?;
        for line in bodyseg_pipeline::describe_parser_files(&config) {
            text.push_str(&line);
            text.push('\n');
        }
    }
    print_stdout(&text)?;
    Ok(Vec::new())
}

/// Prints to stdout; a closed pipe (`bodyseg eval ... | head`) is not an error.
fn print_stdout(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(anyhow::Error::new(e).context("cannot write to stdout"))
        }
        _ => Ok(()),
    }
}
