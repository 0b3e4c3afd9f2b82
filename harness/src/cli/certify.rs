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
use gcl_harness::report::shell_command;
use gcl_host::target::open;
use gcl_model::escape::printable;

/// Arguments of `gcl certify`.
#[derive(Debug, clap::Args)]
#[command(
    override_usage = "gcl certify --target TARGET [--key FILE] [--out DIR] [OPTIONS]\n       \
gcl certify --verify DIR [--pubkey FILE]\n       gcl certify --keygen FILE",
    after_help = "A certificate covers the whole suite at MUST and SHOULD. --skip, --only, --fault and --suite \
change what runs (and --known-failures what counts), so they are refused unless --partial is given; a partial certificate says so in its verdict \
(`PARTIAL: 12 of 336 cases`), and so does one where cases did not run (--no). Every option that changed what ran \
is recorded in the certificate and the reports.\n\nKeys: --keygen FILE writes an Ed25519 private key to FILE \
(PKCS#8 PEM, mode 0600) and its public key to FILE.pub (SPKI PEM); `openssl genpkey -algorithm ed25519` keys work \
too. --key FILE signs the bundle's manifest into MANIFEST.sig. --verify checks the manifest, the signature (against \
--pubkey FILE when given) and that the certificate agrees with the bundled report.json; an unsigned bundle is \
reported as unsigned. Without --pubkey, --verify says that authenticity was not checked and exits 1 unless \
--allow-unverified is given. Known failures (--known-failures) narrow a certificate as a skip does: they need \
--partial, and the certificate names the excused cases.\n\nExit codes: 0 certified (or, with --verify, intact and \
signed by --pubkey, or intact with --allow-unverified); 1 a case failed or nothing ran (or the bundle was tampered \
with, is unsigned while --pubkey was given, or its authenticity was not checked); 2 usage or infrastructure error (a missing \
bundle folder, an unreadable key).\n\nExamples:\n  gcl certify --keygen ~/gcl-lab-key.pem\n  gcl certify --target \
serial:/dev/ttyUSB0 --profile bh8-262-4.3 \\\n      --key ~/gcl-lab-key.pem --out reports/cert\n  gcl certify --verify \
reports/cert --pubkey ~/gcl-lab-key.pem.pub"
)]
pub struct Args {
    /// Check the bundle in DIR (manifest, signature, agreement with its report) instead of
    /// running anything.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["target", "out", "key", "keygen", "partial"])]
    verify: Option<PathBuf>,
    /// With --verify: the public key (PEM) the bundle must be signed by. Without it nothing
    /// says who made the bundle, and --verify exits 1 unless --allow-unverified is given.
    #[arg(long, value_name = "FILE", requires = "verify")]
    pubkey: Option<PathBuf>,
    /// With --verify and no --pubkey: exit 0 for an intact bundle although its authenticity
    /// was not checked (it checks only that the files match the manifest and the report).
    #[arg(long, requires = "verify", conflicts_with = "pubkey")]
    allow_unverified: bool,
    /// Make a key pair: the private key in FILE, the public key in FILE.pub.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["target", "out", "key", "partial"])]
    keygen: Option<PathBuf>,
    /// Sign the bundle with this private key (PKCS#8 PEM).
    #[arg(long, value_name = "FILE")]
    key: Option<PathBuf>,
    /// Allow --skip, --only, --fault, --suite and --known-failures: the certificate's verdict
    /// says PARTIAL.
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
    let mut w = super::stdio::out();
    if let Some(path) = &args.keygen {
        return keygen(path, &mut w);
    }
    if let Some(dir) = &args.verify {
        return verify_bundle(&args, dir, &mut w);
    }
    let Some(suite_args) = &args.suite else {
        anyhow::bail!("give --target (to certify a hand), --verify DIR (to check a bundle) or --keygen FILE");
    };
    if !args.partial {
        refuse_partial(suite_args)?;
    }
    // Read the key before the run, so a bad key costs seconds, not a whole suite.
    let key = args.key.as_deref().map(load_signing_key).transpose()?;
    refuse_full_out(&args.out)?;
    certify_hand(&args, suite_args, key.as_ref(), &mut w)
}

/// `--keygen`: writes the key pair and says where.
fn keygen(path: &std::path::Path, w: &mut impl Write) -> anyhow::Result<u8> {
    let public = generate_key(path)?;
    writeln!(
        w,
        "wrote the private key {} and the public key {} (fingerprint {})",
        path.display(),
        public_key_path(path).display(),
        fingerprint(&public)
    )?;
    Ok(EXIT_OK)
}

/// `--verify`: checks the bundle in `dir` and says what it found; the exit code.
fn verify_bundle(args: &Args, dir: &std::path::Path, w: &mut impl Write) -> anyhow::Result<u8> {
    let trusted = args.pubkey.as_deref().map(load_verifying_key).transpose()?;
    match verify(dir, trusted.as_ref())? {
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
                printable(&cert.date),
                printable(&cert.profile),
                printable(&cert.suite_hash),
                cert.clauses.len(),
                printable(&cert.verdict)
            )?;
            if !cert.excused.is_empty() {
                writeln!(w, "  known failures excused (not covered): {}", printable(&cert.excused.join(", ")))?;
            }
            if matches!(v.signed, Signed::ByTrustedKey(_)) {
                return Ok(EXIT_OK);
            }
            // Without a trusted key, "intact" says only that the files agree with each
            // other: a forger who re-signs with their own key, or writes no signature,
            // makes a bundle that is just as intact.
            writeln!(
                w,
                "AUTHENTICITY NOT CHECKED: no --pubkey was given, so nothing says who made this bundle; a re-signed \
or unsigned forgery verifies the same. Give --pubkey FILE{}",
                if args.allow_unverified { "" } else { " (or --allow-unverified to accept it anyway)" }
            )?;
            Ok(if args.allow_unverified { EXIT_OK } else { EXIT_FAIL })
        }
        Err(problems) => {
            writeln!(w, "TAMPERED: {}", printable(&dir.display().to_string()))?;
            for p in problems {
                writeln!(w, "  {}", printable(&p.to_string()))?;
            }
            Ok(EXIT_FAIL)
        }
    }
}

/// Refuses the options that change what a certificate covers (without `--partial`).
fn refuse_partial(suite_args: &SuiteArgs) -> anyhow::Result<()> {
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
    // A known failure excuses a case exactly as a skip does: the certificate does not
    // cover it.
    if suite_args.known_failures.is_some() {
        changed.push("--known-failures");
    }
    if !changed.is_empty() {
        anyhow::bail!(
            "{} {} what a certificate covers; give --partial to write a certificate that says it is partial",
            changed.join(", "),
            if changed.len() == 1 { "changes" } else { "change" }
        );
    }
    Ok(())
}

/// Refuses an `--out` folder that holds anything.
fn refuse_full_out(out: &std::path::Path) -> anyhow::Result<()> {
    // Empty: nothing in it but the lock file a certify that failed before its run left.
    let lock_name = std::ffi::OsStr::new(gcl_harness::outputs::LOCK_FILE);
    if out.exists()
        && std::fs::read_dir(out).map(|mut d| d.any(|e| e.map_or(true, |e| e.file_name() != lock_name))).unwrap_or(true)
    {
        anyhow::bail!("{} exists and is not empty; choose a new --out", out.display());
    }
    Ok(())
}

/// Runs the suite against the hand, writes the bundle (signed with `key`) and prints the
/// certificate; the exit code.
fn certify_hand(
    args: &Args,
    suite_args: &SuiteArgs,
    key: Option<&ed25519_dalek::SigningKey>,
    w: &mut impl Write,
) -> anyhow::Result<u8> {
    let (opts, cases) = prepare(suite_args, LevelFilter::Should, true)?;
    let cases_total = cases.iter().filter(|c| LevelFilter::Should.admits(c.level())).count();
    // The firmware's own words first, so a certificate names what was tested.
    let vers = firmware_words(&opts)?;
    // Held until the bundle is written: a second certify on the same folder is refused.
    let held = gcl_harness::outputs::OutLock::acquire(&args.out, "certify")?;
    let lock_file = args.out.join(gcl_harness::outputs::LOCK_FILE);
    let mut out = run_with_progress(&opts, &cases, Some(&args.out), false, "gcl certify")?;
    record_options(&mut out.report, suite_args, &opts.profile);
    out.report.options.partial = args.partial;
    out.report.kind = gcl_harness::report::ReportKind::Certify;
    out.report.certificate = Some(gcl_harness::report::CertificateFacts {
        cases_total,
        firmware_version: vers,
        signed_by: key.map(|k| fingerprint(&k.verifying_key())),
    });
    let report = &out.report;
    let cert = Certificate::of_run(report);
    // The streamed results are part of the run's record, but the bundle is the final word.
    let _ = std::fs::remove_file(args.out.join("results.jsonl"));
    // The lock file is ours and no part of the bundle; the lock itself holds until the bundle
    // is written.
    let _ = std::fs::remove_file(&lock_file);
    write_bundle(&args.out, &cert, report, &out.transcripts, key)?;
    drop(held);
    print_certificate(args, key, report, &cert, w)?;
    Ok(if cert.is_pass() || (cert.partial && report.passed()) { EXIT_OK } else { EXIT_FAIL })
}

/// The firmware's own words (`VERS`), after a liveness check.
fn firmware_words(opts: &gcl_harness::conform::ConformOptions) -> anyhow::Result<Vec<String>> {
    let timeout = opts.step_timeout.unwrap_or(Duration::from_secs(5));
    let mut link = open(&opts.target, &opts.open).with_context(|| format!("opening {}", opts.target))?;
    gcl_harness::conform::liveness(link.as_mut(), &opts.profile, timeout)?;
    Ok(firmware_version(link.as_mut(), &opts.profile, timeout)?)
}

/// Prints the run's summary, the certificate and how to check its bundle.
fn print_certificate(
    args: &Args,
    key: Option<&ed25519_dalek::SigningKey>,
    report: &gcl_harness::report::RunReport,
    cert: &Certificate,
    w: &mut impl Write,
) -> anyhow::Result<()> {
    write!(w, "{}", printable(&summary_text(report)))?;
    writeln!(w, "  firmware: {}", printable(&cert.firmware_version.join(" / ")))?;
    writeln!(w, "  certificate verdict: {}", cert.verdict)?;
    if !cert.excused.is_empty() {
        writeln!(w, "  known failures excused (not covered): {}", printable(&cert.excused.join(", ")))?;
    }
    // The check to run is one that can pass: a signed bundle against its public key (the
    // `--keygen` pair's FILE.pub when it is there); an unsigned one only for agreeing with
    // itself, which --verify refuses to call a pass without --allow-unverified.
    let (how, check) = match (key, &args.key) {
        (Some(k), Some(path)) => {
            let public = public_key_path(path);
            let verify = ["gcl", "certify", "--verify", &args.out.display().to_string(), "--pubkey"].map(String::from);
            let check = if public.is_file() {
                shell_command(&[&verify[..], &[public.display().to_string()]].concat())
            } else {
                // A placeholder for the user to fill in, outside the quoted words.
                format!(
                    "{} PUBLIC-KEY-FILE (the public key of {})",
                    shell_command(&verify),
                    fingerprint(&k.verifying_key())
                )
            };
            (format!("signed by key {}", fingerprint(&k.verifying_key())), check)
        }
        _ => (
            "unsigned (give --key to sign it)".to_string(),
            shell_command(&["gcl", "certify", "--verify", &args.out.display().to_string(), "--allow-unverified"]),
        ),
    };
    writeln!(w, "  certificate bundle: {}, {how} (check it with `{check}`)", args.out.display())?;
    Ok(())
}
