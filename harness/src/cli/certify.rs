//! `gcl certify`: run the suite at the MUST and SHOULD levels and write a signed certificate
//! bundle, make a signing key pair with `--keygen`, or check a bundle with `--verify`.

use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;

use super::conform::{SuiteArgs, prepare, record_options, run_with_progress, summary_text};
use super::{EXIT_FAIL, EXIT_OK};
use gcl_harness::certify::{
    Certificate, Signed, fingerprint, generate_key, load_signing_key, load_verifying_key, public_key_path, verify,
    write_bundle,
};
use gcl_harness::conform::{LevelFilter, firmware_version};
use gcl_host::target::open;

/// Arguments of `gcl certify`.
#[derive(Debug, clap::Args)]
#[command(
    override_usage = "gcl certify --target TARGET [--key FILE] [--out DIR] [OPTIONS]\n       \
gcl certify --verify DIR [--pubkey FILE]\n       gcl certify --keygen FILE",
    after_help = "A certificate covers the whole suite at MUST and SHOULD. --skip, --only, --fault and --suite \
change what runs, so they are refused unless --partial is given; a partial certificate says so in its verdict \
(`PARTIAL: 12 of 336 cases`), and so does one where cases did not run (--no). Every option that changed what ran \
is recorded in the certificate and the reports.\n\nKeys: --keygen FILE writes an Ed25519 private key to FILE \
(PKCS#8 PEM, mode 0600) and its public key to FILE.pub (SPKI PEM); `openssl genpkey -algorithm ed25519` keys work \
too. --key FILE signs the bundle's manifest into MANIFEST.sig. --verify checks the manifest, the signature (against \
--pubkey FILE when given) and that the certificate agrees with the bundled report.json; an unsigned bundle is \
reported as unsigned.\n\nExit codes: 0 certified (or, with --verify, intact); 1 a case failed or nothing ran (or \
the bundle was tampered with, or is unsigned while --pubkey was given); 2 usage or infrastructure error (a missing \
bundle folder, an unreadable key).\n\nExamples:\n  gcl certify --keygen lab-key.pem\n  gcl certify --target \
serial:/dev/ttyUSB0?baud=9600 --profile bh8-262-4.3 --key lab-key.pem --out cert-4.34\n  gcl certify --verify \
cert-4.34 --pubkey lab-key.pem.pub"
)]
pub struct Args {
    /// Check the bundle in DIR (manifest, signature, agreement with its report) instead of
    /// running anything.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["target", "out", "key", "keygen", "partial"])]
    verify: Option<PathBuf>,
    /// With --verify: the public key (PEM) the bundle must be signed by.
    #[arg(long, value_name = "FILE", requires = "verify")]
    pubkey: Option<PathBuf>,
    /// Make a key pair: the private key in FILE, the public key in FILE.pub.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["target", "out", "key", "partial"])]
    keygen: Option<PathBuf>,
    /// Sign the bundle with this private key (PKCS#8 PEM).
    #[arg(long, value_name = "FILE")]
    key: Option<PathBuf>,
    /// Allow --skip, --only, --fault and --suite: the certificate's verdict says PARTIAL.
    #[arg(long)]
    partial: bool,
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
    if let Some(path) = &args.keygen {
        let public = generate_key(path)?;
        writeln!(
            w,
            "wrote the private key {} and the public key {} (fingerprint {})",
            path.display(),
            public_key_path(path).display(),
            fingerprint(&public)
        )?;
        return Ok(EXIT_OK);
    }
    if let Some(dir) = &args.verify {
        let trusted = args.pubkey.as_deref().map(load_verifying_key).transpose()?;
        return match verify(dir, trusted.as_ref())? {
            Ok(v) => {
                let cert = &v.certificate;
                let signed = match &v.signed {
                    Signed::Unsigned => "unsigned: anybody could have written it".to_string(),
                    Signed::ByTrustedKey(k) => format!("signed by the trusted key {}", fingerprint(k)),
                    Signed::ByUncheckedKey(k) => {
                        format!("signed by key {} (give --pubkey to check whose it is)", fingerprint(k))
                    }
                };
                writeln!(
                    w,
                    "intact, {signed}: {} ({}), profile {}, suite {}, {} clauses, verdict {}",
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
        anyhow::bail!("give --target (to certify a hand), --verify DIR (to check a bundle) or --keygen FILE");
    };
    if !args.partial {
        let mut changed = Vec::new();
        if !suite_args.skip.is_empty() {
            changed.push("--skip");
        }
        if !suite_args.only.is_empty() {
            changed.push("--only");
        }
        if !suite_args.fault.is_empty() {
            changed.push("--fault");
        }
        if suite_args.suite.is_some() {
            changed.push("--suite");
        }
        if !suite_args.skip_decision.is_empty() {
            changed.push("--skip-decision");
        }
        if !changed.is_empty() {
            anyhow::bail!(
                "{} change what a certificate covers; give --partial to write a certificate that says it is partial",
                changed.join(", ")
            );
        }
    }
    // Read the key before the run, so a bad key costs seconds, not a whole suite.
    let key = args.key.as_deref().map(load_signing_key).transpose()?;
    if args.out.exists() && std::fs::read_dir(&args.out).map(|mut d| d.next().is_some()).unwrap_or(true) {
        anyhow::bail!("{} exists and is not empty; choose a new --out", args.out.display());
    }
    let (opts, cases) = prepare(suite_args, LevelFilter::Should, true)?;
    let cases_total = cases.iter().filter(|c| LevelFilter::Should.admits(c.level())).count();
    // The firmware's own words first, so a certificate names what was tested.
    let timeout = opts.step_timeout.unwrap_or(Duration::from_secs(5));
    let vers = {
        let mut link = open(&opts.target, &opts.open).with_context(|| format!("opening {}", opts.target))?;
        gcl_harness::conform::liveness(link.as_mut(), &opts.profile, timeout)?;
        firmware_version(link.as_mut(), &opts.profile, timeout)?
    };
    let mut out = run_with_progress(&opts, &cases, Some(&args.out), false, "gcl certify")?;
    record_options(&mut out.report, suite_args);
    out.report.options.partial = args.partial;
    out.report.kind = gcl_harness::report::ReportKind::Certify;
    let report = &out.report;
    let cert = Certificate::of_run(report, vers, cases_total, args.partial);
    // The streamed results are part of the run's record, but the bundle is the final word.
    let _ = std::fs::remove_file(args.out.join("results.jsonl"));
    write_bundle(&args.out, &cert, report, &out.transcripts, key.as_ref())?;
    write!(w, "{}", summary_text(report))?;
    writeln!(w, "  firmware: {}", cert.firmware_version.join(" / "))?;
    writeln!(w, "  certificate verdict: {}", cert.verdict)?;
    let how = match &key {
        Some(k) => format!("signed by key {}", fingerprint(&k.verifying_key())),
        None => "unsigned (give --key to sign it)".to_string(),
    };
    writeln!(
        w,
        "  certificate bundle: {}, {how} (check it with `gcl certify --verify {}`)",
        args.out.display(),
        args.out.display()
    )?;
    Ok(if cert.is_pass() || (cert.partial && report.passed()) { EXIT_OK } else { EXIT_FAIL })
}
