//! fmirs: validate and simulate an FMU (FMI 2.0 or 3.0) with fmi-rs, the engine of the
//! Modelica Association's fmusim. The command line mirrors fmusim's options that the
//! tests use (fmusim docs/index.md, "simulate" and "validate"); the simulation and the
//! checks are fmi-rs's own (fmi_rs::sim::{fmi2, fmi3}::{cs, me}::simulate and
//! ModelDescription::validate), not artibus code.
//!
//!   fmirs validate FMU
//!   fmirs simulate FMU [--interface-type cs|me] [--event-mode-used] [--early-return-allowed]
//!                      [--start-time T] [--stop-time T] [--output-interval H]
//!                      [--fixed-step-size H] [--start-value NAME=VALUE]... [--output-file F]
//!
//! Exit status 0 when the FMU passed, 1 with the reason on stderr otherwise.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use fmi_rs::model_description::{DefaultExperiment, FMIMajorVersion, peek_fmi_major_version};
use fmi_rs::sim::solver::ForwardEulerFactory;
use fmi_rs::zip::{extract_zip_archive, get_zip_contents};

#[derive(Default)]
struct Args {
    command: String,
    fmu: String,
    interface_type: Option<String>,
    event_mode_used: bool,
    early_return_allowed: bool,
    start_time: Option<f64>,
    stop_time: Option<f64>,
    output_interval: Option<f64>,
    fixed_step_size: Option<f64>,
    start_values: Vec<(String, String)>,
    output_file: Option<PathBuf>,
}

fn number(flag: &str, text: Option<String>) -> Result<f64, String> {
    let text = text.ok_or(format!("{flag} needs a value"))?;
    text.parse().map_err(|_| format!("{flag} {text}: not a number"))
}

fn parse_args() -> Result<Args, String> {
    let mut it = std::env::args().skip(1);
    let mut a = Args { command: it.next().unwrap_or_default(), ..Args::default() };
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--interface-type" => a.interface_type = it.next(),
            "--event-mode-used" => a.event_mode_used = true,
            "--early-return-allowed" => a.early_return_allowed = true,
            "--start-time" => a.start_time = Some(number(&arg, it.next())?),
            "--stop-time" => a.stop_time = Some(number(&arg, it.next())?),
            "--output-interval" => a.output_interval = Some(number(&arg, it.next())?),
            "--fixed-step-size" => a.fixed_step_size = Some(number(&arg, it.next())?),
            "--output-file" => a.output_file = it.next().map(PathBuf::from),
            "--start-value" => {
                let kv = it.next().ok_or("--start-value needs NAME=VALUE")?;
                let (k, v) = kv.split_once('=').ok_or(format!("--start-value {kv}: not NAME=VALUE"))?;
                a.start_values.push((k.to_string(), v.to_string()));
            }
            _ if arg.starts_with("--") => return Err(format!("unknown option {arg}")),
            _ => a.fmu = arg,
        }
    }
    if !matches!(a.command.as_str(), "validate" | "simulate") || a.fmu.is_empty() {
        return Err("usage: fmirs validate|simulate FMU [options]".into());
    }
    Ok(a)
}

/// start, stop, tolerance and output interval: the arguments, else the default experiment,
/// else fmusim's defaults (stop = start + 1, tolerance 1e-4, 500 intervals)
fn steps(a: &Args, de: Option<&DefaultExperiment>, fixed: Option<f64>) -> (f64, f64, f64, f64) {
    let get = |v: Option<&Option<String>>| v.and_then(|s| s.as_ref()).and_then(|s| s.parse::<f64>().ok());
    let start = a.start_time.or(get(de.map(|d| &d.startTime))).unwrap_or(0.0);
    let stop = a.stop_time.or(get(de.map(|d| &d.stopTime))).unwrap_or(start + 1.0);
    let tolerance = get(de.map(|d| &d.tolerance)).unwrap_or(1e-4);
    let interval = a.output_interval.or(get(de.map(|d| &d.stepSize))).or(fixed).unwrap_or((stop - start) / 500.0);
    (start, stop, tolerance, interval)
}

fn validate(a: &Args, dir: &Path, version: FMIMajorVersion) -> Result<(), String> {
    let mut problems: Vec<String> = vec![];
    let entries = get_zip_contents(&a.fmu).map_err(|e| e.to_string())?;
    for e in entries {
        if e.starts_with(['.', '/']) || e.contains('\\') {
            problems.push(format!("ZIP entry '{e}': starts with '.' or '/', or contains '\\'"));
        }
    }
    let xml = dir.join("modelDescription.xml");
    match version {
        FMIMajorVersion::V2 => {
            let md = fmi_rs::model_description::fmi2::ModelDescription::from_path(&xml).map_err(|e| e.to_string())?;
            problems.extend(md.validate().into_iter().map(|p| p.message));
        }
        FMIMajorVersion::V3 => {
            let md = fmi_rs::model_description::fmi3::ModelDescription::from_path(&xml).map_err(|e| e.to_string())?;
            problems.extend(md.validate().into_iter().map(|p| p.message));
        }
    }
    let build = dir.join("sources/buildDescription.xml");
    if build.is_file()
        && let Err(e) = fmi_rs::build_description::BuildDescription::from_file(&build)
    {
        problems.push(format!("sources/buildDescription.xml: {e}"));
    }
    if problems.is_empty() { Ok(()) } else { Err(problems.join("\n")) }
}

/// Model Exchange (--interface-type me, or an FMU without Co-Simulation) or Co-Simulation
fn model_exchange(a: &Args, has_co_simulation: bool) -> Result<bool, String> {
    match a.interface_type.as_deref() {
        Some("me") => Ok(true),
        Some("cs") => Ok(false),
        Some(t) => Err(format!("--interface-type {t}: expected cs or me")),
        None => Ok(!has_co_simulation),
    }
}

/// fmi-rs's simulation of FMI version `$v` (fmi2 or fmi3) with the outputs recorded, the
/// result written to --output-file: the same for both versions but for their types
macro_rules! record {
    ($v:ident, $a:expr, $md:expr, $settings:expr, $outputs:expr, $interval:expr) => {{
        use fmi_rs::sim::$v::{Trajectories, csv::write_csv, recorder::Recorder};
        let recorder = Arc::new(Recorder::new(Trajectories::new($md.clone(), $outputs)));
        let result = if model_exchange($a, $md.coSimulation.is_some())? {
            let euler = ForwardEulerFactory { fixed_step_size: $a.fixed_step_size.unwrap_or($interval) };
            fmi_rs::sim::$v::me::simulate(&$settings, &euler, None, recorder.clone())
        } else {
            fmi_rs::sim::$v::cs::simulate(&$settings, None, recorder.clone())
        };
        result.map_err(|e| e.to_string())?;
        let trajectories = Arc::try_unwrap(recorder).map_err(|_| "the recorder is still shared")?.trajectories.into_inner();
        if let Some(f) = &$a.output_file {
            write_csv(&trajectories, f).map_err(|e| format!("{}: {e}", f.display()))?;
        }
        Ok(())
    }};
}

fn simulate3(a: &Args, dir: &Path) -> Result<(), String> {
    use fmi_rs::model_description::fmi3::{Causality, ModelDescription};
    use fmi_rs::sim::fmi3::SimulationSettings;
    let md = Arc::new(ModelDescription::from_path(&dir.join("modelDescription.xml")).map_err(|e| e.to_string())?);
    let outputs = md.modelVariables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, _)| i).collect();
    let fixed = md.coSimulation.as_ref().and_then(|c| c.fixedInternalStepSize.as_ref()).and_then(|s| s.parse().ok());
    let (start_time, stop_time, tolerance, output_interval) = steps(a, md.defaultExperiment.as_ref(), fixed);
    let settings = SimulationSettings {
        unzipdir: dir.to_path_buf(), model_description: md.clone(), library_kind: fmi_rs::fmi3::LibraryKind::Native,
        enable_dae: false, start_time, stop_time, visible: false, logging_on: false, set_stop_time: true,
        output_interval, log_time_scale: false, tolerance, set_tolerance: false, start_values: a.start_values.clone(),
        log_fmi_calls: false, intermediate_update: false, input_file: None,
        early_return_allowed: a.early_return_allowed, event_mode_used: a.event_mode_used, log_file: None,
        initial_fmu_state_file: None, final_fmu_state_file: None,
    };
    record!(fmi3, a, md, settings, outputs, output_interval)
}

fn simulate2(a: &Args, dir: &Path) -> Result<(), String> {
    use fmi_rs::model_description::fmi2::{Causality, ModelDescription};
    use fmi_rs::sim::fmi2::SimulationSettings;
    let md = Arc::new(ModelDescription::from_path(&dir.join("modelDescription.xml")).map_err(|e| e.to_string())?);
    let outputs = md.modelVariables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, _)| i).collect();
    let (start_time, stop_time, tolerance, output_interval) = steps(a, md.defaultExperiment.as_ref(), None);
    let settings = SimulationSettings {
        unzipdir: dir.to_path_buf(), model_description: md.clone(), start_time, stop_time, logging_on: false,
        set_stop_time: true, output_interval, log_time_scale: false, tolerance, set_tolerance: false,
        start_values: a.start_values.clone(), log_fmi_calls: false, input_file: None,
        early_return_allowed: a.early_return_allowed, event_mode_used: a.event_mode_used, log_file: None,
        initial_fmu_state_file: None, final_fmu_state_file: None,
    };
    record!(fmi2, a, md, settings, outputs, output_interval)
}

fn run() -> Result<(), String> {
    let a = parse_args()?;
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    extract_zip_archive(&a.fmu, dir.path()).map_err(|e| format!("{}: {e}", a.fmu))?;
    let version = peek_fmi_major_version(&dir.path().join("modelDescription.xml")).map_err(|e| format!("{}: {e}", a.fmu))?;
    match (a.command.as_str(), version) {
        ("validate", v) => validate(&a, dir.path(), v),
        (_, FMIMajorVersion::V3) => simulate3(&a, dir.path()),
        (_, FMIMajorVersion::V2) => simulate2(&a, dir.path()),
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fmirs: {e}");
            ExitCode::FAILURE
        }
    }
}
