//! `gcl certify`: run the suite at the MUST and SHOULD levels and write a certificate
//! bundle, or check a bundle for tampering with `--verify`.

use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;

use super::conform::{SuiteArgs, prepare, run_with_progress, summary_text};
use super::{EXIT_FAIL, EXIT_OK};
use crate::certify::{Certificate, ClauseVerdict, verify, write_bundle};
use crate::conform::{LevelFilter, firmware_version};
use crate::report::Verdict;
use crate::target::open;

/// Arguments of `gcl certify`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Exit codes: 0 certified (or, with --verify, intact); 1 a case failed (or the bundle was \
tampered with); 2 usage or infrastructure error.\n\nExamples:\n  gcl certify --target \
serial:/dev/ttyUSB0?baud=9600 --profile bh8-262-4.3 --out cert-4.34\n  gcl certify --verify cert-4.34")]
pub struct Args {
    /// Check the bundle in DIR against its manifest instead of running anything.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["target", "out"])]
    verify: Option<PathBuf>,
    /// Where to write the bundle (it must not exist yet, or be empty).
    #[arg(long, value_name = "DIR", default_value = "certificate")]
    out: PathBuf,
    /// The hand and suite options (as for `gcl conform`).
    #[command(flatten)]
    suite: Option<SuiteArgs>,
}

/// Runs `gcl certify`.
pub fn run(args: Args) -> anyhow::Result<u8> {
    let mut w = std::io::stdout().lock();
    if let Some(dir) = &args.verify {
        return match verify(dir)? {
            Ok(cert) => {
                writeln!(
                    w,
                    "intact: {} ({}), profile {}, suite {}, {} clauses, verdict {}",
                    dir.display(),
                    cert.date,
                    cert.profile,
                    cert.suite_hash,
                    cert.clauses.len(),
                    cert.verdict
                )?;
                Ok(EXIT_OK)
            }
            Err(problems) => {
                writeln!(w, "TAMPERED: {}", dir.display())?;
                for p in problems {
                    writeln!(w, "  {p}")?;
                }
                Ok(EXIT_FAIL)
            }
        };
    }
    let Some(suite_args) = &args.suite else {
        anyhow::bail!("give --target (to certify a hand) or --verify DIR (to check a bundle)");
    };
    if args.out.exists() && std::fs::read_dir(&args.out).map(|mut d| d.next().is_some()).unwrap_or(true) {
        anyhow::bail!("{} exists and is not empty; choose a new --out", args.out.display());
    }
    let (opts, cases) = prepare(suite_args, LevelFilter::Should, true)?;
    // The firmware's own words first, so a certificate names what was tested.
    let timeout = opts.step_timeout.unwrap_or(Duration::from_secs(5));
    let vers = {
        let mut link = open(&opts.target, &opts.open).with_context(|| format!("opening {}", opts.target))?;
        crate::conform::liveness(link.as_mut(), &opts.profile, timeout)?;
        firmware_version(link.as_mut(), &opts.profile, timeout)?
    };
    let out = run_with_progress(&opts, &cases, Some(&args.out), false)?;
    let report = &out.report;
    let cert = Certificate {
        firmware_version: vers,
        profile: report.profile.clone(),
        target: report.target.clone(),
        suite_hash: report.suite_hash.clone(),
        harness_version: report.tool.clone(),
        date: report.started.clone(),
        levels: vec!["MUST".into(), "SHOULD".into()],
        verdict: if report.passed() { Verdict::Pass } else { Verdict::Fail },
        clauses: report
            .clauses
            .iter()
            .map(|c| ClauseVerdict { clause: c.clause.clone(), verdict: c.verdict, cases: c.cases.len() })
            .collect(),
    };
    // The streamed results are part of the run's record, but the bundle is the final word.
    let _ = std::fs::remove_file(args.out.join("results.jsonl"));
    write_bundle(&args.out, &cert, report, &out.transcripts)?;
    write!(w, "{}", summary_text(report))?;
    writeln!(w, "  firmware: {}", cert.firmware_version.join(" / "))?;
    writeln!(
        w,
        "  certificate bundle: {} (check it with `gcl certify --verify {}`)",
        args.out.display(),
        args.out.display()
    )?;
    Ok(if report.passed() { EXIT_OK } else { EXIT_FAIL })
}
