//! `goniofit fit`: a measurement file in, a fit report out.

use super::fit_args::{Command, FitArgs, CLI};
use crate::error::Error;
use crate::fit::dataset::{batch, fit_dataset_near, DatasetFit, Outcome};
use crate::io::{self, Dataset, ReadOptions};
use crate::report::{self, RunInfo};
use crate::settings::Settings;
use anyhow::Context;
use goniofit_lm::Stop;
use std::path::{Path, PathBuf};

/// The units a dataset's fit is reported in (those of its report's setting), without the
/// rest of the setting: λ's unit and the measured quantity.
fn units_of(s: &Settings, ds: &Dataset) -> report::Units {
    report::Units {
        length: s.wavelength_unit(ds),
        quantity: s.quantity_for(ds, CLI).0,
        radiance: None,
    }
}

/// The input file's absolute path, size and SHA-256.
pub(crate) fn input_info(path: &Path) -> anyhow::Result<report::setting::InputInfo> {
    let io_error = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io_error)?;
    let (sha256, bytes) = report::checksum::sha256_hex_of(file).map_err(io_error)?;
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    Ok(report::setting::InputInfo {
        path: abs.display().to_string(),
        sha256,
        bytes,
    })
}

/// The command line as typed, for the report (control and bidi characters escaped).
fn command_line() -> String {
    std::env::args_os()
        .map(|a| io::shown_text(&a.to_string_lossy()).into_owned())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The fit of dataset `ds` with the command's settings. `single`: the only dataset of the
/// command (progress shown on a terminal, profile intervals unless `--no-intervals`).
fn dataset_fit(c: &Command, ds: &Dataset, single: bool) -> DatasetFit {
    let mut spec = c.settings.dataset_fit(ds, single);
    spec.config.lm.progress = single && c.args.show_progress();
    spec
}

/// Fit one dataset with every candidate model; keep the lowest BIC among the usable fits.
/// Every fit shares `stop` (the command's `--timeout` and signals); `near`: the fit of its
/// neighbour in the input (`--warm-start`), whose optima each candidate is first started at.
fn fit_one(
    c: &Command,
    (label, ds): (String, Dataset),
    single: bool,
    stop: &Stop,
    near: Option<&Outcome>,
) -> anyhow::Result<Outcome> {
    let mut spec = dataset_fit(c, &ds, single);
    spec.config.lm.stop = Some(stop.clone());
    let context = format!("{label}: fitting model {}", c.settings.model);
    fit_dataset_near(&spec, label, ds, near).context(context)
}

pub(crate) fn run(args: FitArgs) -> anyhow::Result<u8> {
    // Refused before any file is read.
    if args.json && summary_on_stdout(&args) {
        return Err(Error::Usage(
            "--json and --summary - both write standard output; give --summary a file".into(),
        )
        .into());
    }
    let settings = args.settings()?;
    settings.check(CLI)?;
    // From the start Ctrl-C, SIGTERM and SIGHUP stop the command instead of ending the
    // process, and `--timeout` counts from here: reading stops within a MiB (nothing
    // fitted, exit 3), a fit reports its best point (exit 3).
    let stop = Stop::new(settings.fit_config(&settings.model, false).lm.timeout, None);
    let (threads, note) = crate::settings::threads(CLI, settings.threads)?;
    if let Some(note) = note {
        eprintln!("goniofit: {note}");
    }
    let opts = settings.read_options()?;
    let c = Command { args, settings };
    let (args, model) = (&c.args, &c.settings.model);
    let heartbeat = super::heartbeat::Heartbeat::start(!args.quiet);
    heartbeat.stage(format!("reading {}", io::shown(&args.file[0])));
    // Every input is read (and checked) before any fit starts.
    let t_read = std::time::Instant::now();
    let (jobs, files) = read_jobs(args, &opts, &stop)?;
    let read = t_read.elapsed().as_secs_f64();
    let single = jobs.len() == 1;
    heartbeat.stage(match single {
        true => format!("fitting {} (model {model})", jobs[0].0),
        false => format!("fitting {} datasets (model {model})", jobs.len()),
    });
    if !single && args.residuals.is_some() {
        return Err(Error::Usage(
            "--residuals takes one dataset; fit several files or groups one at a time for it"
                .into(),
        )
        .into());
    }
    let t0 = std::time::Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    if !single && rows_only(args) {
        return rows_batch(&c, jobs, &stop, (&pool, &heartbeat), (read, t0));
    }
    let (outcomes, skipped) = fit_jobs(&c, jobs, &stop, (&pool, &heartbeat), |o| o)?;
    let wall = t0.elapsed().as_secs_f64();
    heartbeat.stage("writing the reports and outputs");
    // The reports' parts of a big batch are built on the fit's threads.
    use rayon::prelude::*;
    let infos: Vec<RunInfo> = pool.install(|| {
        outcomes
            .par_iter()
            .map(|o| run_info(&c.settings, o, &files))
            .collect()
    });
    let threads = pool.current_num_threads();
    pool.install(|| print_reports(&c, &outcomes, &infos, &skipped, wall, threads))?;
    if single {
        super::fit_outputs::write_single_outputs(&c, &outcomes[0], &infos[0])?;
    } else {
        super::fit_outputs::write_batch_outputs(&c, &outcomes, &infos, &skipped)?;
    }
    if super::stages::wanted() {
        let times: Vec<_> = outcomes.iter().map(super::stages::Times::of).collect();
        super::stages::print((read, wall, t0.elapsed().as_secs_f64() - wall), &times);
    }
    let code = exit_code(outcomes.iter().all(usable), &skipped, &stop);
    // The process ends with this command: its memory goes back to the system at once,
    // while freeing a big batch's results vector by vector is serial work at the end.
    std::mem::forget((outcomes, infos));
    Ok(code)
}

/// 0 when every fit converged with its uncertainties and intervals computed, nothing was
/// skipped and no signal came; else 3. A signal that came after the fits (while the
/// outputs were written) still says the run was interrupted: every output is complete, and
/// the exit code is 3.
fn exit_code(all_usable: bool, skipped: &[String], stop: &Stop) -> u8 {
    let interrupted = stop.requested() == Some(goniofit_lm::Termination::Interrupted);
    if all_usable && !interrupted && skipped.is_empty() {
        0
    } else {
        3
    }
}

/// An input file and what the reports say of it (absolute path, size, SHA-256).
type InputFile = (PathBuf, report::setting::InputInfo);

/// Whether a fit did all it was asked: converged, with its figures and intervals computed.
fn usable(o: &Outcome) -> bool {
    o.result.converged() && !o.intervals_stopped && o.result.fitted_computed
}

/// A batch whose output is the summary rows alone ([`rows_only`]): each fit kept as its
/// row once no later fit starts from it, the rows written after the last fit, with the
/// batch's messages, stage timing and exit code as for any batch.
fn rows_batch(
    c: &Command,
    jobs: Vec<(String, Dataset)>,
    stop: &Stop,
    (pool, heartbeat): (&rayon::ThreadPool, &super::heartbeat::Heartbeat),
    (read, t0): (f64, std::time::Instant),
) -> anyhow::Result<u8> {
    let (kept, skipped) = fit_jobs(c, jobs, stop, (pool, heartbeat), |o| {
        let row = report::summary::row(&o.label, &o.result, &units_of(&c.settings, &o.dataset));
        (row, usable(&o), super::stages::Times::of(&o))
    })?;
    let wall = t0.elapsed().as_secs_f64();
    let (rows, rest): (Vec<report::summary::Row>, Vec<_>) =
        kept.into_iter().map(|(row, u, t)| (row, (u, t))).unzip();
    let csv = report::summary::csv_rows(&rows);
    io::write_csv(Path::new("-"), &report::summary::csv_header(), &csv)?;
    batch_messages(&c.args, &rows, &skipped, wall, pool.current_num_threads());
    if super::stages::wanted() {
        let times: Vec<_> = rest.iter().map(|k| k.1).collect();
        super::stages::print((read, wall, t0.elapsed().as_secs_f64() - wall), &times);
    }
    Ok(exit_code(rest.iter().all(|k| k.0), &skipped, stop))
}

/// Read every input file into the datasets to fit (one per file, or one per group with
/// `--by-group`), with each file's checksum and size.
#[allow(clippy::type_complexity)]
fn read_jobs(
    args: &FitArgs,
    opts: &ReadOptions,
    stop: &Stop,
) -> anyhow::Result<(Vec<(String, Dataset)>, Vec<InputFile>)> {
    let mut jobs: Vec<(String, Dataset)> = Vec::new();
    let mut files = Vec::new();
    for file in &args.file {
        // The raw rows are kept only for the residuals file (which passes them through).
        let bar = reading_bar(file, args.show_progress());
        // The file's checksum is taken on another thread while it is parsed.
        let (ds, info) = rayon::join(
            || {
                io::read_dataset_with(file, opts, args.residuals.is_some(), &|done| {
                    bar.set_position(done);
                    stop.requested().map_or(Ok(()), |why| Err(why.describe()))
                })
            },
            || input_info(file),
        );
        let ds = ds?;
        bar.finish_and_clear();
        crate::fit::dataset::check_magnitudes(&ds)?;
        files.push((file.clone(), info?));
        if !args.by_group {
            jobs.push((io::shown(file), ds));
            continue;
        }
        let groups = ds.channel_groups();
        if groups.is_empty() {
            return Err(Error::Usage(format!(
                "{}: --by-group needs groups: ASTM channels, a group column, or a wavelength column",
                io::shown(file)
            ))
            .into());
        }
        // Each group's dataset without the labels (the groups hold them).
        let mut ds = ds;
        ds.channel = None;
        let shown = io::shown(file);
        for (name, idx) in groups {
            let label = format!("{shown} [{}]", io::shown_text(&name));
            jobs.push((label, ds.subset(&idx)));
        }
    }
    Ok((jobs, files))
}

/// Fit every job in `pool` (one job: on the calling thread's pool with the fit's own
/// progress; several: in parallel, with a bar of datasets fitted), all sharing `stop`.
/// Returns the fits and the labels of the datasets a stop request kept from a result.
fn fit_jobs<K: Send>(
    c: &Command,
    mut jobs: Vec<(String, Dataset)>,
    stop: &Stop,
    (pool, heartbeat): (&rayon::ThreadPool, &super::heartbeat::Heartbeat),
    keep: impl Fn(Outcome) -> K + Sync + Send,
) -> anyhow::Result<(Vec<K>, Vec<String>)> {
    if jobs.len() == 1 {
        let job = jobs.pop().expect("one job");
        let one = pool.install(|| fit_one(c, job, true, stop, None))?;
        return Ok((vec![keep(one)], Vec::new()));
    }
    let bar = if c.args.show_progress() {
        super::recover::progress_bar(jobs.len() as u64, "datasets fitted")
    } else {
        indicatif::ProgressBar::hidden()
    };
    heartbeat.count(jobs.len() as u64);
    let fit = |(label, ds): (String, Dataset), previous: Option<&anyhow::Result<Outcome>>| {
        // After a stop request no further dataset is started.
        if stop.is_requested() {
            return Err(not_fitted(&label, stop));
        }
        let near = previous.and_then(|r| r.as_ref().ok());
        let outcome = fit_one(c, (label, ds), false, stop, near);
        bar.inc(1);
        heartbeat.inc();
        outcome
    };
    let warm = c.settings.warm_start;
    let done = pool.install(|| batch::in_chains_kept(jobs, warm, fit, |r| r.map(&keep)));
    bar.finish_and_clear();
    fitted_and_stopped(done)
}

/// Whether the summary rows on standard output are all the command writes of a batch
/// (`--summary -` without `--json`, `--html`, `--plot` or `--residuals`): no fit needs to
/// be kept once its row is made.
fn rows_only(args: &FitArgs) -> bool {
    summary_on_stdout(args)
        && !args.json
        && args.html.is_none()
        && args.plot.is_none()
        && args.residuals.is_none()
}

/// The error of a dataset `label` a stop request kept from being fitted.
fn not_fitted(label: &str, stop: &Stop) -> anyhow::Error {
    let why = stop.requested().map_or("stopped", |t| t.describe());
    anyhow::Error::new(Error::Stopped(format!(
        "{label}: {why} before its fit started"
    )))
}

/// The fits of a batch, and the labels of the datasets a stop request kept from a result
/// ([`Error::Stopped`]: not started, or stopped before the first evaluation on the whole
/// data finished). Any other error ends the command.
fn fitted_and_stopped<T>(
    outcomes: Vec<anyhow::Result<T>>,
) -> anyhow::Result<(Vec<T>, Vec<String>)> {
    let mut fitted = Vec::new();
    let mut skipped = Vec::new();
    for o in outcomes {
        match o {
            Ok(o) => fitted.push(o),
            Err(e) if super::is_stopped(&e) => skipped.push(format!("{e:#}")),
            Err(e) => return Err(e),
        }
    }
    Ok((fitted, skipped))
}

/// What a report says about the run besides the fit: input, command, setting, intervals.
fn run_info(s: &Settings, o: &Outcome, files: &[InputFile]) -> RunInfo {
    let file = files
        .iter()
        .find(|(p, _)| *p == o.dataset.path)
        .map(|(_, i)| i.clone())
        .unwrap_or_default();
    RunInfo {
        input: o.label.clone(),
        command: command_line(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        setting: report::outcome::setting(&o.dataset, &o.input, (s, CLI), file),
        intervals: o.intervals.clone(),
        interval_seconds: o.interval_seconds,
    }
}

/// Print the reports (JSON or text, with the summary table after several fits or a joint
/// one), write `--summary`, and say on standard error how long several fits took.
fn print_reports(
    c: &Command,
    outcomes: &[Outcome],
    infos: &[RunInfo],
    skipped: &[String],
    wall: f64,
    threads: usize,
) -> anyhow::Result<()> {
    // One dataset to fit (a batch with all but one not fitted is still a batch).
    let single = outcomes.len() == 1 && skipped.is_empty();
    use rayon::prelude::*;
    let rows: Vec<report::summary::Row> = outcomes
        .par_iter()
        .zip(infos)
        .map(|(o, i)| report::summary::row(&o.label, &o.result, &i.setting.units))
        .collect();
    let args = &c.args;
    if args.json && single {
        let v = report::outcome::report(&outcomes[0], &infos[0], &c.settings);
        io::print_stdout(&format!("{}\n", serde_json::to_string_pretty(&v)?))?;
    } else if args.json {
        let head = serde_json::json!({
            "fits": FITS_MARK,
            "datasets": outcomes.len(),
            "not_converged": rows.iter().filter(|r| !r.converged).count(),
            "not_fitted": skipped,
            "seconds": wall,
            "threads": threads,
            "summary": summary_json(&rows),
        });
        print_batch_json(&head, outcomes, infos, &c.settings)?;
    } else if summary_on_stdout(args) {
        // The summary rows are the standard output (written below).
    } else {
        // Each report written as it is rendered (a big batch never holds all its text).
        let joint = outcomes.iter().any(|o| o.input.channel_names.len() > 1);
        io::write_atomic(Path::new("-"), |w| {
            for (o, i) in outcomes.iter().zip(infos) {
                w.write_all(report::outcome::to_text(o, i).as_bytes())?;
            }
            if !single || joint {
                w.write_all(report::summary::table(&rows).as_bytes())?;
            }
            Ok(())
        })?;
    }
    if let Some(path) = &args.summary {
        io::write_csv(
            path,
            &report::summary::csv_header(),
            &report::summary::csv_rows(&rows),
        )?;
    }
    if !single {
        batch_messages(args, &rows, skipped, wall, threads);
    }
    Ok(())
}

/// A batch's messages on standard error: the datasets a stop kept from a fit, and (unless
/// `--quiet`) how many were fitted, how fast, and how many did not converge.
fn batch_messages(
    args: &FitArgs,
    rows: &[report::summary::Row],
    skipped: &[String],
    wall: f64,
    threads: usize,
) {
    if !skipped.is_empty() {
        eprintln!(
            "goniofit: {} of {} datasets not fitted:\n  {}",
            skipped.len(),
            skipped.len() + rows.len(),
            skipped.join("\n  ")
        );
    }
    if !args.quiet {
        let failed =
            report::summary::not_converged(rows).map_or(String::new(), |t| format!("; {t}"));
        eprintln!(
            "goniofit: fitted {} datasets in {:.3} s ({:.1} datasets/s) on {} threads{failed}",
            rows.len(),
            wall,
            rows.len() as f64 / wall,
            threads
        );
    }
}

/// Whether `--summary -` makes the summary CSV the standard output (in place of the text
/// reports: a big batch's natural output).
fn summary_on_stdout(args: &FitArgs) -> bool {
    args.summary.as_deref() == Some(Path::new("-"))
}

/// Stands for the batch report's `fits` array in [`print_batch_json`]'s head.
const FITS_MARK: &str = "\u{1}fits\u{1}";

/// The batch's JSON report on standard output, the bytes `serde_json::to_string_pretty`
/// gives of the whole object, written as it is produced: `head` (every key, with `fits`
/// standing for the array) around each fit's object serialised and written in turn, so
/// that a batch of many fits never holds its whole report in memory.
fn print_batch_json(
    head: &serde_json::Value,
    outcomes: &[Outcome],
    infos: &[RunInfo],
    settings: &Settings,
) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(head)?;
    let mark = serde_json::to_string(FITS_MARK)?;
    let (before, after) = text
        .split_once(&mark)
        .ok_or_else(|| anyhow::anyhow!("the batch report's head has no fits"))?;
    io::write_atomic(Path::new("-"), |w| {
        w.write_all(before.as_bytes())?;
        if outcomes.is_empty() {
            w.write_all(b"[]")?;
        }
        for (k, (o, i)) in outcomes.iter().zip(infos).enumerate() {
            let fit = report::outcome::report(o, i, settings);
            let fit = serde_json::to_string_pretty(&fit).map_err(std::io::Error::other)?;
            // Two levels deeper than alone: JSON strings hold no raw line breaks.
            w.write_all(if k == 0 { b"[\n    " } else { b",\n    " })?;
            w.write_all(fit.replace('\n', "\n    ").as_bytes())?;
        }
        if !outcomes.is_empty() {
            w.write_all(b"\n  ]")?;
        }
        w.write_all(after.as_bytes())?;
        w.write_all(b"\n")
    })?;
    Ok(())
}

/// A bar of bytes read from `file` on standard error (hidden unless `show`).
fn reading_bar(file: &Path, show: bool) -> indicatif::ProgressBar {
    let len = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
    if !show || len < READING_BAR_BYTES {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(super::recover::bar_style(
        "reading {msg} [{bar:30}] {bytes}/{total_bytes} {elapsed} (eta {eta})",
    ));
    bar.set_message(io::shown(file));
    bar
}

/// Files smaller than this are read without a bar (they take milliseconds).
const READING_BAR_BYTES: u64 = 4 << 20;

/// The summary rows as JSON objects (the CSV's columns).
fn summary_json(rows: &[report::summary::Row]) -> serde_json::Value {
    let csv = report::summary::csv_rows(rows);
    serde_json::Value::Array(
        csv.into_iter()
            .map(|r| {
                let m: serde_json::Map<String, serde_json::Value> = report::summary::csv_header()
                    .into_iter()
                    .zip(r)
                    .map(|(k, v)| (k, serde_json::Value::String(v)))
                    .collect();
                serde_json::Value::Object(m)
            })
            .collect(),
    )
}
