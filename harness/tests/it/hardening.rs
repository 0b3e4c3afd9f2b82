//! Issue 9, as an adversarial user tries it: bad files (huge, endless, FIFOs), selections
//! that select nothing, certificates that would lie, busy ports, profiles from files, absurd
//! bauds, and a first run outside the repository. Every child is bounded in time.

use crate::sim_support;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use gcl_harness::report::{RunReport, Verdict};
use sim_support::{GCL, SimProcess, Transport};

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs `gcl ARGS` in `cwd`, killing it if it has not ended within `limit`.
fn gcl_in(cwd: Option<&Path>, args: &[&str], limit: Duration) -> Run {
    let mut cmd = Command::new(GCL);
    cmd.args(args).stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    if let Some(d) = cwd {
        cmd.current_dir(d);
    }
    let mut child = cmd.spawn().unwrap();
    let end = Instant::now() + limit;
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > end {
            let _ = child.kill();
            let _ = child.wait();
            panic!("gcl {args:?} did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let out = child.wait_with_output().unwrap();
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

fn gcl(args: &[&str]) -> Run {
    gcl_in(None, args, Duration::from_secs(120))
}

fn mkfifo(p: &Path) {
    nix::unistd::mkfifo(p, nix::sys::stat::Mode::from_bits_truncate(0o600)).unwrap();
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn report(dir: &Path) -> RunReport {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

const SUITE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite");

#[test]
fn no_file_input_is_read_whole_or_waited_on() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("x.gcl");
    mkfifo(&fifo);
    // A sparse 1 GiB file costs nothing on disk; reading it whole would cost 1 GiB.
    let big = dir.path().join("big.gcl");
    std::fs::File::create(&big).unwrap().set_len(1 << 30).unwrap();
    let quick = Duration::from_secs(30);
    for (args, says) in [
        (vec!["replay", "/dev/zero"], "character device"),
        (vec!["replay", s(&fifo)], "named pipe"),
        (vec!["replay", s(&big)], "larger than"),
        (vec!["record", "--target", "sim:seed", "--script", s(&big)], "larger than"),
        (vec!["record", "--target", "sim:seed", "--script", s(&fifo)], "named pipe"),
        (vec!["conform", "--target", "sim:seed", "--known-failures", s(&fifo)], "named pipe"),
        (vec!["conform", "--target", "sim:seed", "--known-failures", s(&big)], "larger than"),
        (vec!["explain", "--profile", s(&fifo), "HI"], "named pipe"),
        (vec!["explain", "--profile", s(&big), "HI"], "larger than"),
        (vec!["sim", "--stdio", "--scenario", s(&fifo)], "named pipe"),
        (vec!["sim", "--stdio", "--eeprom", "/dev/zero"], "character device"),
        (vec!["certify", "--verify", s(dir.path()), "--pubkey", s(&fifo)], "named pipe"),
    ] {
        let r = gcl_in(None, &args, quick);
        assert_eq!(r.code, Some(2), "{args:?}: {}{}", r.stdout, r.stderr);
        assert!(r.stderr.contains(says), "{args:?}: {}", r.stderr);
    }
    // A FIFO named like a golden in a suite directory is refused, not waited on.
    let suite = dir.path().join("suite");
    std::fs::create_dir_all(suite.join("seed")).unwrap();
    std::fs::copy(Path::new(SUITE).join("seed/framing-echo.gcl"), suite.join("seed/framing-echo.gcl")).unwrap();
    mkfifo(&suite.join("seed/x.gcl"));
    let r = gcl_in(None, &["conform", "--target", "sim:seed", "--suite", s(&suite)], quick);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("x.gcl") && r.stderr.contains("named pipe"), "{}", r.stderr);
}

#[test]
fn record_replaces_its_output_atomically() {
    use std::os::unix::fs::MetadataExt;
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("hi.script");
    std::fs::write(&script, "id: hi\nHI\n").unwrap();
    let out = dir.path().join("hi.gcl");
    std::fs::write(&out, "old contents\n").unwrap();
    let before = std::fs::metadata(&out).unwrap().ino();
    let r = gcl(&["record", "--target", "sim:seed", "--script", s(&script), "--out", s(&out)]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    // A new file renamed over the old one (a write in place keeps the inode, and a kill in
    // the middle of it leaves an empty or torn file).
    assert_ne!(std::fs::metadata(&out).unwrap().ino(), before, "the output was rewritten in place");
    assert!(std::fs::read_to_string(&out).unwrap().starts_with("gcl-transcript"));
    let names: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names.len(), 2, "no temporary file left behind: {names:?}");
}

#[test]
fn only_matching_nothing_is_a_usage_error_and_a_run_of_nothing_is_no_pass() {
    let r = gcl(&["conform", "--target", "sim:seed", "--only", "nonesuch-*"]);
    assert_eq!(r.code, Some(2), "{}{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("--only `nonesuch-*` matches no case"), "{}", r.stderr);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    let r = gcl(&["conform", "--target", "sim:seed", "--skip", "*"]);
    assert_eq!(r.code, Some(1), "{}", r.stdout);
    assert!(r.stdout.contains("no case ran") && r.stdout.contains("result: FAIL"), "{}", r.stdout);
}

/// A firmware team's hand already differs: `--write-known-failures` keeps today's failures as
/// the baseline, with which the same hand passes, a hand with one more bug fails on that bug
/// alone (in a listed case too, when it fails that case otherwise), and a hand where a listed failure went away fails as XPASS (the list cannot go
/// stale).
#[test]
fn a_run_writes_the_known_failures_its_next_run_takes() {
    let dir = tempfile::tempdir().unwrap();
    let known = dir.path().join("known.toml");
    let conform = |faults: &[&str], extra: &[&str]| {
        let mut a = vec!["conform", "--target", "sim:seed", "--quiet"];
        for f in faults {
            a.extend(["--fault", f]);
        }
        a.extend(extra);
        gcl(&a)
    };
    let r = conform(&["fget-reversed"], &["--write-known-failures", s(&known)]);
    assert_eq!(r.code, Some(1), "{}{}", r.stdout, r.stderr);
    let text = std::fs::read_to_string(&known).unwrap();
    let listed = text.matches("[[failure]]").count();
    assert!(listed > 100, "{listed} failures listed");
    assert!(r.stdout.contains(&format!("({listed} known failures)")), "{}", r.stdout);
    assert!(text.contains("case = \"framing-echo\"") && text.contains("profile = \"seed\""), "{text}");
    // The same hand: every failure is known.
    let r = conform(&["fget-reversed"], &["--known-failures", s(&known)]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    // One more bug: the run fails, and only on cases that were passing.
    let r = conform(&["fget-reversed", "lfap-little-endian"], &["--known-failures", s(&known)]);
    assert_eq!(r.code, Some(1), "{}{}", r.stdout, r.stderr);
    let failing: Vec<&str> = r.stdout.lines().filter(|l| l.trim_start().starts_with("FAIL ")).collect();
    assert!(!failing.is_empty() && failing.iter().all(|l| l.contains("rt-")), "{}", r.stdout);
    assert!(r.stdout.contains("(LFAP)"), "{}", r.stdout);
    // Each entry names how its case fails; a bug that breaks listed cases otherwise (here
    // earlier: a prefixed command no longer refused) fails the run instead of hiding there.
    assert!(text.contains("how = \"step 4: order at FGET\""), "{text}");
    let r = conform(&["fget-reversed", "prefix-not-refused"], &["--known-failures", s(&known)]);
    assert_eq!(r.code, Some(1), "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("fails otherwise than its known failure: known `step"), "{}", r.stdout);
    // The listed bug fixed: the listed cases pass and fail the run as XPASS.
    let r = conform(&[], &["--known-failures", s(&known)]);
    assert_eq!(r.code, Some(1), "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("XPASS"), "{}", r.stdout);
}

#[test]
fn a_known_failure_that_matches_nothing_is_reported_and_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let known = dir.path().join("known.toml");
    std::fs::write(
        &known,
        "[[failure]]\ncase = \"framing-ech\"\nreason = \"a typo\"\n\n[[failure]]\ncase = \"x\"\nprofile = \"bh8-262-4.3\"\nreason = \"another profile's\"\n",
    )
    .unwrap();
    let rep = dir.path().join("rep");
    let r = gcl(&[
        "conform",
        "--target",
        "sim:seed",
        "--only",
        "framing-echo",
        "--known-failures",
        s(&known),
        "--report",
        s(&rep),
    ]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("warning: known failure `framing-ech`") && r.stderr.contains("matches no case"));
    assert!(!r.stderr.contains("`x`"), "entries for other profiles are not this run's: {}", r.stderr);
    let rep = report(&rep);
    assert_eq!(rep.options.known_failures.len(), 1);
    assert!(!rep.options.known_failures[0].matched);
    assert_eq!(rep.options.only, vec!["framing-echo".to_string()]);
    assert!(r.stdout.contains("matching no case: framing-ech"), "{}", r.stdout);
}

#[test]
fn certify_refuses_selections_unless_partial_and_says_partial() {
    let dir = tempfile::tempdir().unwrap();
    for extra in [&["--skip", "rt-*"][..], &["--only", "framing-*"], &["--fault", "crlf"], &["--suite", SUITE]] {
        let out = dir.path().join("refused");
        let mut args = vec!["certify", "--target", "sim:seed", "--out", s(&out)];
        args.extend(extra);
        let r = gcl(&args);
        assert_eq!(r.code, Some(2), "{extra:?}: {}", r.stdout);
        assert!(r.stderr.contains(extra[0]) && r.stderr.contains("--partial"), "{}", r.stderr);
        // One option changes; several change (issue 21 item 4).
        assert!(r.stderr.contains(&format!("{} changes what a certificate covers", extra[0])), "{}", r.stderr);
        assert!(!out.exists(), "nothing written");
    }
    let r = gcl(&[
        "certify",
        "--target",
        "sim:seed",
        "--only",
        "framing-*",
        "--fault",
        "crlf",
        "--out",
        s(&dir.path().join("x")),
    ]);
    assert!(r.stderr.contains("--only, --fault change what a certificate covers"), "{}", r.stderr);
    // Everything skipped: not a PASS, even when partial.
    let none = dir.path().join("none");
    let r = gcl(&["certify", "--target", "sim:seed", "--partial", "--skip", "*", "--out", s(&none)]);
    assert_eq!(r.code, Some(1), "{}", r.stdout);
    let cert: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(none.join("certificate.json")).unwrap()).unwrap();
    assert!(cert["verdict"].as_str().unwrap().starts_with("FAIL (PARTIAL: 0 of "), "{}", cert["verdict"]);
    // A partial run: its verdict, its options, in the certificate and every report.
    let part = dir.path().join("part");
    let r = gcl(&["certify", "--target", "sim:seed", "--partial", "--only", "framing-*", "--out", s(&part)]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    let cert: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(part.join("certificate.json")).unwrap()).unwrap();
    let verdict = cert["verdict"].as_str().unwrap();
    assert!(verdict.starts_with("PARTIAL: ") && verdict.ends_with(" cases"), "{verdict}");
    assert_eq!(cert["options"]["only"], serde_json::json!(["framing-*"]));
    assert_eq!(cert["options"]["partial"], true);
    let rep = report(&part);
    assert_eq!(rep.options.only, vec!["framing-*".to_string()]);
    let ran: Vec<_> = rep.cases.iter().filter(|c| c.verdict != Verdict::Skip).collect();
    assert!(!ran.is_empty() && ran.iter().all(|c| c.id.starts_with("framing-") && c.verdict == Verdict::Pass));
    let junit = std::fs::read_to_string(part.join("junit.xml")).unwrap();
    assert!(junit.contains("<property name=\"gcl.only\" value=\"framing-*\"/>"), "{junit}");
    let html = std::fs::read_to_string(part.join("report.html")).unwrap();
    assert!(html.contains("<th><code>--only</code></th><td>framing-*</td>"), "{html}");
    let r = gcl(&["certify", "--verify", s(&part), "--allow-unverified"]);
    assert_eq!(r.code, Some(0), "{}", r.stdout);
    assert!(r.stdout.contains("unsigned") && r.stdout.contains("verdict PARTIAL: "), "{}", r.stdout);
}

#[test]
fn signed_certificates_verify_and_forgeries_do_not() {
    let dir = tempfile::tempdir().unwrap();
    let key = dir.path().join("lab.pem");
    let r = gcl(&["certify", "--keygen", s(&key)]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let public = dir.path().join("lab.pem.pub");
    assert!(std::fs::read_to_string(&public).unwrap().starts_with("-----BEGIN PUBLIC KEY-----"));
    let cert = dir.path().join("cert");
    let r = gcl(&[
        "certify",
        "--target",
        "sim:seed",
        "--partial",
        "--only",
        "framing-*",
        "--key",
        s(&key),
        "--out",
        s(&cert),
    ]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("signed by key"), "{}", r.stdout);
    let r = gcl(&["certify", "--verify", s(&cert), "--pubkey", s(&public)]);
    assert_eq!(r.code, Some(0), "{}", r.stdout);
    assert!(r.stdout.contains("intact, signed by the trusted key"), "{}", r.stdout);
    // Forge: say PASS, and rewrite the manifest as `sha256sum` would.
    let c = cert.join("certificate.json");
    let text = std::fs::read_to_string(&c).unwrap();
    let forged = regex_free_replace_verdict(&text, "PASS");
    std::fs::write(&c, forged).unwrap();
    let mut manifest = String::new();
    for line in std::fs::read_to_string(cert.join("MANIFEST.sha256")).unwrap().lines() {
        let (_, path) = line.split_once("  ").unwrap();
        let hash = gcl_harness::certify::sha256_hex(&std::fs::read(cert.join(path)).unwrap());
        manifest.push_str(&format!("{hash}  {path}\n"));
    }
    std::fs::write(cert.join("MANIFEST.sha256"), manifest).unwrap();
    let r = gcl(&["certify", "--verify", s(&cert), "--pubkey", s(&public)]);
    assert_eq!(r.code, Some(1), "{}", r.stdout);
    assert!(r.stdout.contains("TAMPERED") && r.stdout.contains("signature"), "{}", r.stdout);
    // Without the signature, the certificate still disagrees with its report.
    std::fs::remove_file(cert.join("MANIFEST.sig")).unwrap();
    let r = gcl(&["certify", "--verify", s(&cert)]);
    assert_eq!(r.code, Some(1), "{}", r.stdout);
    assert!(r.stdout.contains("disagrees with report.json"), "{}", r.stdout);
    // A missing folder is a usage error.
    let r = gcl(&["certify", "--verify", s(&dir.path().join("nonesuch"))]);
    assert_eq!(r.code, Some(2), "{}", r.stdout);
    assert!(!r.stdout.contains("TAMPERED"));
    // --help does not make --target look required for --verify.
    let r = gcl(&["certify", "--help"]);
    assert!(r.stdout.contains("gcl certify --verify DIR [--pubkey FILE]"), "{}", r.stdout);
}

/// Issue 32 item 5: a profile file that declares a built-in profile's id (the seed spec with
/// `id = "bh8-262-4.3"`) is certified as the file it is, with its hash; a certificate
/// rewritten and re-signed to claim the built-in is caught by `--verify`, whose own built-in
/// spec and suite do not match what ran.
#[test]
fn a_profile_file_claiming_a_built_in_id_is_certified_as_the_file_it_is() {
    use gcl_harness::certify::{Certificate, load_signing_key, write_bundle};
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("fake.toml");
    let seed = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec/seed.toml")).unwrap();
    assert!(seed.contains("\nid = \"seed\"\n"));
    std::fs::write(&fake, seed.replacen("\nid = \"seed\"\n", "\nid = \"bh8-262-4.3\"\n", 1)).unwrap();
    let key = dir.path().join("lab.pem");
    assert_eq!(gcl(&["certify", "--keygen", s(&key)]).code, Some(0));
    let public = dir.path().join("lab.pem.pub");
    let cert = dir.path().join("cert");
    let r = gcl(&["certify", "--target", "sim", "--profile", s(&fake), "--key", s(&key), "--out", s(&cert)]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cert.join("certificate.json")).unwrap()).unwrap();
    let profile = c["profile"].as_str().unwrap();
    assert!(
        profile.starts_with(&format!(
            "{} (a profile file declaring id bh8-262-4.3, not that built-in profile; sha256 ",
            fake.display()
        )),
        "{profile}"
    );
    assert_eq!(c["profile_spec"]["origin"], "file");
    assert_eq!(c["profile_spec"]["id"], "bh8-262-4.3");
    let r = gcl(&["certify", "--verify", s(&cert), "--pubkey", s(&public)]);
    assert_eq!(r.code, Some(0), "{}", r.stdout);
    assert!(r.stdout.contains(&format!("profile {profile},")), "{}", r.stdout);
    assert!(!r.stdout.contains("profile bh8-262-4.3,"), "{}", r.stdout);
    let page = std::fs::read_to_string(cert.join("report.html")).unwrap();
    assert!(page.contains("fake.toml (a profile file declaring id bh8-262-4.3, not that built-in profile"), "{page}");
    // The same spec from a file that is the built-in's (spec/seed.toml) is that built-in.
    let same = dir.path().join("same");
    let seed_file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec/seed.toml");
    let r = gcl(&["certify", "--target", "sim", "--profile", s(&seed_file), "--out", s(&same)]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    let c2: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(same.join("certificate.json")).unwrap()).unwrap();
    assert_eq!((c2["profile"].as_str(), c2["profile_spec"]["origin"].as_str()), (Some("seed"), Some("builtin")));

    // A forger with the key claims the built-in: first keeping the fake spec's hash, then with
    // the built-in's hash (the suite hash still is the fake's).
    let builtin = gcl_model::Profile::builtin("bh8-262-4.3").unwrap();
    let builtin_hash = gcl_harness::report::ProfileSpec::digest(&builtin);
    let signing = load_signing_key(&key).unwrap();
    let transcripts: Vec<(String, String)> = std::fs::read_dir(cert.join("transcripts"))
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            (p.file_stem().unwrap().to_string_lossy().into_owned(), std::fs::read_to_string(&p).unwrap())
        })
        .collect();
    for (name, hash, says) in [
        ("forged-spec", None, "but the spec that ran"),
        ("forged-hash", Some(builtin_hash.clone()), "is not that of the built-in profile bh8-262-4.3's suite"),
    ] {
        let mut report = report(&cert);
        let spec = report.profile_spec.as_mut().unwrap();
        spec.origin = gcl_harness::report::ProfileOrigin::Builtin;
        spec.name = "bh8-262-4.3".into();
        if let Some(h) = &hash {
            spec.sha256 = h.clone();
        }
        let forged = Certificate::of_run(&report);
        assert_eq!(forged.profile, "bh8-262-4.3");
        let out = dir.path().join(name);
        write_bundle(&out, &forged, &report, &transcripts, Some(&signing)).unwrap();
        let r = gcl(&["certify", "--verify", s(&out), "--pubkey", s(&public)]);
        assert_eq!(r.code, Some(1), "{name}: {}", r.stdout);
        assert!(r.stdout.contains("TAMPERED") && r.stdout.contains(says), "{name}: {}", r.stdout);
    }
}

/// Issue 32 item 5: a `--baseline` recorded under one profile explains nothing under another:
/// it is refused, naming both; a baseline that is used is named in the reports.
#[test]
fn a_baseline_of_another_profile_is_refused_and_a_baseline_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let found = dir.path().join("found");
    let fuzz = |target: &str, more: &[&str]| {
        let mut a = vec!["fuzz", "device", "--target", target, "--fault", "fget-reversed", "--runs", "60", "--quiet"];
        a.extend(more);
        gcl(&a)
    };
    let r = fuzz("sim:seed", &["--out", s(&found)]);
    assert_eq!(r.code, Some(1), "{}{}", r.stdout, r.stderr);
    let r = fuzz("sim:bh8-262-4.3", &["--baseline", s(&found)]);
    assert_eq!(r.code, Some(2), "{}{}", r.stdout, r.stderr);
    assert!(
        r.stderr.contains("was recorded on profile seed, and this campaign's profile is bh8-262-4.3"),
        "{}",
        r.stderr
    );
    // One sentence, spaced as one (issue 39 item 16: a string broken over lines without `\`
    // put a run of 18 spaces in it, twice).
    assert!(r.stderr.contains("a baseline says what is known of a hand under its own profile only"), "{}", r.stderr);
    assert!(!r.stderr.contains("  "), "{}", r.stderr);
    assert!(!r.stdout.contains("known"), "{}", r.stdout);
    let rep = dir.path().join("rep");
    let r = fuzz("sim:seed", &["--baseline", s(&found), "--report", s(&rep)]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(rep.join("fuzz-device.json")).unwrap()).unwrap();
    let named = j["provenance"]["options"]["baseline"].as_str().unwrap();
    assert!(named.starts_with(&format!("{} (", found.display())) && named.contains("profile seed"), "{named}");
    let page = std::fs::read_to_string(rep.join("fuzz-device.html")).unwrap();
    assert!(page.contains("<code>--baseline</code>") && page.contains(&found.display().to_string()), "{page}");
}

/// Issue 39 item 11: a baseline is known by the spec it was recorded on, not by the id the
/// spec declares: a baseline of the built-in `seed` explains nothing on a doctored file that
/// declares `id = "seed"` (it did: exit 0, the finding "known: in the baseline"), and a
/// finding that names no spec (an older gcl's) counts only against the built-in.
#[test]
fn a_baseline_of_the_built_in_excuses_nothing_on_a_file_declaring_its_id() {
    let dir = tempfile::tempdir().unwrap();
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec");
    // The seed spec with another finger limit, under the built-in's id, beside the files it
    // includes.
    std::fs::create_dir(dir.path().join("shared")).unwrap();
    for e in std::fs::read_dir(spec.join("shared")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), dir.path().join("shared").join(e.file_name())).unwrap();
    }
    let seed = std::fs::read_to_string(spec.join("seed.toml")).unwrap();
    assert!(seed.contains("\nfinger_limit = 17800\n"));
    let doctored = dir.path().join("doctored.toml");
    std::fs::write(&doctored, seed.replacen("\nfinger_limit = 17800\n", "\nfinger_limit = 17000\n", 1)).unwrap();
    let found = dir.path().join("found");
    let fuzz = |more: &[&str]| {
        let mut a =
            vec!["fuzz", "device", "--target", "sim:seed", "--fault", "fget-reversed", "--runs", "60", "--quiet"];
        a.extend(more);
        gcl(&a)
    };
    let r = fuzz(&["--out", s(&found)]);
    assert_eq!(r.code, Some(1), "{}{}", r.stdout, r.stderr);
    let r = fuzz(&["--profile", s(&doctored), "--baseline", s(&found)]);
    assert_eq!(r.code, Some(2), "{}{}", r.stdout, r.stderr);
    assert!(
        r.stderr.contains("names a spec with sha256 ")
            && r.stderr.contains(&format!(
                "this campaign's profile is {} (a profile file declaring id seed",
                doctored.display()
            )),
        "{}",
        r.stderr
    );
    assert!(!r.stdout.contains("known"), "{}", r.stdout);
    // The built-in itself: the baseline explains its finding.
    assert_eq!(fuzz(&["--baseline", s(&found)]).code, Some(0));
    // Findings written before they named their spec: taken as the built-in's.
    for e in std::fs::read_dir(&found).unwrap() {
        let p = e.unwrap().path();
        let text = std::fs::read_to_string(&p).unwrap();
        let old: String =
            text.lines().filter(|l| !l.starts_with("x-profile-sha256:")).map(|l| format!("{l}\n")).collect();
        assert_ne!(old, text, "a finding names its spec");
        std::fs::write(&p, old).unwrap();
    }
    assert_eq!(fuzz(&["--baseline", s(&found)]).code, Some(0));
    let r = fuzz(&["--profile", s(&doctored), "--baseline", s(&found)]);
    assert_eq!(r.code, Some(2), "{}{}", r.stdout, r.stderr);
    assert!(
        r.stderr.contains("names no spec (written by an older gcl, so taken as the built-in seed)"),
        "{}",
        r.stderr
    );
}

/// Replaces the value of the top-level `"verdict"` of a pretty-printed certificate.
fn regex_free_replace_verdict(text: &str, to: &str) -> String {
    text.lines()
        .map(|l| if l.starts_with("  \"verdict\": ") { format!("  \"verdict\": \"{to}\",") } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_busy_serial_port_is_one_clear_line_and_exit_2() {
    let sim = SimProcess::start(Transport::Pty, &["--profile", "seed"]);
    let target = sim.target();
    let path = target.strip_prefix("serial:").unwrap().to_string();
    {
        let _held = gcl_host::links::SerialLink::open(&path, 9600).unwrap();
        let r = gcl(&["conform", "--target", &target, "--profile", "seed", "--only", "framing-echo"]);
        assert_eq!(r.code, Some(2), "{}{}", r.stdout, r.stderr);
        assert!(r.stderr.contains("is in use by another program"), "{}", r.stderr);
        assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    }
    // Released on close: the next run opens it.
    let r = gcl(&["conform", "--target", &target, "--profile", "seed", "--only", "framing-echo", "--timeout", "2000"]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
}

#[test]
fn a_profile_file_is_simulated_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let seed = std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../spec/seed.toml")).unwrap();
    let file = dir.path().join("my-seed.toml");
    std::fs::write(&file, seed.replacen("id = \"seed\"", "id = \"my-seed\"", 1)).unwrap();
    let rep = dir.path().join("rep");
    let r = gcl(&["conform", "--target", "sim", "--profile", s(&file), "--only", "framing-*", "--report", s(&rep)]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    assert_eq!(report(&rep).profile, "my-seed");
}

#[test]
fn absurd_bauds_are_refused_and_the_bound_counts_only_pass_and_fail() {
    for args in [
        &["conform", "--target", "sim", "--baud", "0"][..],
        &["conform", "--target", "sim", "--baud", "99999999"],
        &["conform", "--target", "serial:/dev/null?baud=0"],
    ] {
        let r = gcl(args);
        assert_eq!(r.code, Some(2), "{args:?}");
        assert!(r.stderr.contains("baud"), "{}", r.stderr);
    }
    let dir = tempfile::tempdir().unwrap();
    // PASS, FAIL (a range off by one) and TIMEOUT (a prompt without its space never
    // completes an answer) in one run, from two hands.
    let r = gcl(&[
        "conform",
        "--target",
        "sim:seed",
        "--fault",
        "range-off-by-one",
        "--only",
        "param-dp-*",
        "--timeout",
        "200",
        "--baud",
        "9600",
        "--report",
        s(dir.path()),
    ]);
    assert_eq!(r.code, Some(1), "{}", r.stdout);
    let rep = report(dir.path());
    let w = rep.wire.clone().unwrap();
    assert!(rep.summary[&Verdict::Pass] > 0 && rep.summary[&Verdict::Fail] > 0, "{:?}", rep.summary);
    assert_eq!(w.counted_cases, rep.summary[&Verdict::Pass] + rep.summary[&Verdict::Fail]);
    let timeouts = tempfile::tempdir().unwrap();
    let r2 = gcl(&[
        "conform",
        "--target",
        "sim:seed",
        "--fault",
        "prompt-no-space",
        "--only",
        "framing-*",
        "--timeout",
        "200",
        "--baud",
        "9600",
        "--report",
        s(timeouts.path()),
    ]);
    assert_eq!(r2.code, Some(1), "{}", r2.stdout);
    let rep2 = report(timeouts.path());
    assert!(rep2.summary[&Verdict::Timeout] > 0, "{:?}", rep2.summary);
    let w2 = rep2.wire.unwrap();
    assert_eq!(w2.counted_cases, 0, "TIMEOUTs are not line time");
    // Only the pre-flight's exchanges before the cases are.
    assert_eq!(w2.lower_bound_ms, w2.probes_ms);
    assert!(w2.probes_ms > 0.0, "{w2:?}");
    // Full duplex: never more than both directions one after the other, plus motion.
    let serial_ms = (w.bytes_sent + w.bytes_received) as f64 * 10.0 / 9600.0 * 1000.0;
    assert!(w.lower_bound_ms - w.probes_ms < serial_ms + w.motion_ms, "{w:?}");
    assert!(w.lower_bound_ms >= w.bytes_sent.max(w.bytes_received) as f64 * 10.0 / 9600.0 * 1000.0, "{w:?}");
    // The in-process hand keeps simulated time: its run may beat the bound, and then says so.
    assert!(
        r.stdout.contains("PASS/FAIL cases")
            && (r.stdout.contains("full duplex") || r.stdout.contains("no wire-time bound")),
        "{}",
        r.stdout
    );
}

/// A bound the run's own duration refutes is not printed as a bound: a hand that answered a
/// run's bytes faster than their baud allows does not pace its bytes at that baud (an unpaced
/// simulator), and the console and the page say so; report.json keeps the figures.
#[test]
fn a_wire_bound_the_run_beats_is_not_printed_as_a_bound() {
    let dir = tempfile::tempdir().unwrap();
    // At 50 baud the framing cases' bytes take minutes; the unpaced simulator answers them in
    // a second.
    let target = format!("exec:{GCL} sim --stdio --profile seed");
    let r = gcl(&[
        "conform",
        "--target",
        &target,
        "--profile",
        "seed",
        "--only",
        "framing-*",
        "--no",
        "abort-timing",
        "--baud",
        "50",
        "--report",
        s(dir.path()),
    ]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    let w = report(dir.path()).wire.unwrap();
    assert!(w.actual_ms < w.lower_bound_ms && w.ratio < 1.0, "{w:?}");
    assert!(!r.stdout.contains("wire-time lower bound"), "{}", r.stdout);
    assert!(
        r.stdout.contains("no wire-time bound: the run took")
            && r.stdout.contains("so the hand does not pace its bytes at 50 baud"),
        "{}",
        r.stdout
    );
    let html = std::fs::read_to_string(dir.path().join("report.html")).unwrap();
    assert!(html.contains("no wire-time bound: the run took") && !html.contains("Lower bound"), "{html}");
}

/// The run's time includes the pre-flight and the motion-time probe, so the bound counts what
/// they put on the line by the same rule, and says so where the ratio is printed: on a hand in
/// real time the probe's watched close alone is a fifth of a second of the model's time.
#[test]
fn the_wire_bound_counts_the_pre_flight_and_the_motion_time_probe_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let target = format!("exec:{GCL} sim --stdio --profile seed --time real --baud 9600");
    let r = gcl(&[
        "conform",
        "--target",
        &target,
        "--profile",
        "seed",
        "--only",
        "abort-motion-discards-queue",
        "--baud",
        "9600",
        "--report",
        s(dir.path()),
    ]);
    assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
    let w = report(dir.path()).wire.unwrap();
    assert!(w.probes_ms > 200.0, "{w:?}");
    assert!(w.lower_bound_ms > w.probes_ms, "{w:?}");
    assert!(
        r.stdout.contains("and the pre-flight and motion-time probe before them")
            && r.stdout.contains("the whole run, probes included, took"),
        "{}",
        r.stdout
    );
}

#[test]
fn suite_commands_outside_the_repository_read_the_built_in_catalogue_or_say_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    // Listing needs no files: the catalogue is built into gcl (issue 21 item 2), so the
    // advice of `--only`'s error works wherever it is given.
    let r = gcl_in(Some(dir.path()), &["suite", "list", "--profile", "seed"], Duration::from_secs(120));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stdout.lines().any(|l| l.starts_with("seed ") && l.contains(" framing-echo ")), "{}", r.stdout);
    assert!(r.stdout.lines().all(|l| l.starts_with("seed ") || l.contains(" cases: ")), "{}", r.stdout);
    let o =
        gcl_in(Some(dir.path()), &["conform", "--target", "sim:seed", "--only", "no-such-*"], Duration::from_secs(120));
    assert_eq!(o.code, Some(2));
    assert!(o.stderr.contains("`gcl suite list --profile seed` lists them"), "{}", o.stderr);
    // Checking compares committed files, and there are none here or above.
    for args in [&["suite", "check"][..], &["vectors", "check"]] {
        let r = gcl_in(Some(dir.path()), args, Duration::from_secs(120));
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stdout);
        assert!(r.stderr.contains("or any folder above it"), "{}", r.stderr);
        assert!(!r.stdout.contains("missing"), "{}", r.stdout);
    }
    // Inside the repository, from any folder of it, `check` finds the committed suite.
    let deep = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../conformance/src/suite");
    for args in [&["suite", "check"][..], &["vectors", "check"]] {
        let r = gcl_in(Some(&deep), args, Duration::from_secs(300));
        assert_eq!(r.code, Some(0), "{args:?}: {}{}", r.stdout, r.stderr);
        assert!(r.stdout.contains("are fresh"), "{}", r.stdout);
    }
    let r = gcl_in(Some(dir.path()), &["suite", "regenerate"], Duration::from_secs(120));
    assert_eq!(r.code, Some(2), "{}", r.stdout);
    assert!(!dir.path().join("vectors").exists(), "nothing written into the cwd");
}

/// An error is one line that says each cause once: a missing exec target and a missing
/// bundle used to print their cause twice (`...(os error 2): cannot open ...(os error 2)`).
#[test]
fn an_error_says_its_cause_once() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-firmware");
    let target = format!("exec:{}", s(&missing));
    let bundle = dir.path().join("no-such-bundle");
    for args in [
        &["fuzz", "device", "--target", &target, "--runs", "3"][..],
        &["conform", "--target", &target],
        &[
            "replay",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../vectors/suite/seed/framing-echo.gcl"),
            "--target",
            &target,
        ],
        &["fuzz", "host", "--replay", s(&bundle), "--", "true"],
    ] {
        let r = gcl(args);
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
        assert_eq!(r.stderr.trim_end().lines().count(), 1, "{args:?}: {}", r.stderr);
        assert_eq!(r.stderr.matches("(os error 2)").count(), 1, "{args:?}: {}", r.stderr);
    }
}

/// A run that could not start (a port or a firmware that is not there) leaves no report
/// folder behind, nor the parents it made for it (issue 40: `reports/hand` was left holding an
/// empty `results.jsonl`).
#[test]
fn a_run_that_could_not_start_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-port");
    let serial = format!("serial:{}?baud=9600", s(&missing));
    let exec = format!("exec:{}", s(&dir.path().join("no-such-firmware")));
    let reports = dir.path().join("reports");
    let out = reports.join("hand");
    for args in [
        &["conform", "--target", &serial, "--report", s(&out)][..],
        &["conform", "--target", &exec, "--report", s(&out)],
        &["certify", "--target", &serial, "--out", s(&out)],
        &["fuzz", "device", "--target", &exec, "--runs", "3", "--out", s(&out), "--report", s(&reports.join("r"))],
        &["check-host", "--report", s(&out), "--", s(&dir.path().join("no-such-host")), "{port}"],
    ] {
        let r = gcl(args);
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
        assert!(!reports.exists(), "{args:?} left {:?}", std::fs::read_dir(&reports).map(|d| d.count()));
    }
}

/// The check `gcl certify` tells its user to run is one that passes on the bundle it wrote:
/// with `--pubkey` for a signed bundle, with `--allow-unverified` for an unsigned one (a bare
/// `--verify` exits 1 on both: authenticity not checked).
#[test]
fn the_check_certify_prints_passes_on_its_bundle() {
    let dir = tempfile::tempdir().unwrap();
    let key = dir.path().join("lab-key.pem");
    assert_eq!(gcl(&["certify", "--keygen", s(&key)]).code, Some(0));
    for signed in [true, false] {
        let out = dir.path().join(if signed { "signed" } else { "unsigned" });
        let mut args = vec!["certify", "--target", "sim:seed", "--partial", "--only", "framing-*", "--out", s(&out)];
        if signed {
            args.extend(["--key", s(&key)]);
        }
        let r = gcl(&args);
        assert_eq!(r.code, Some(0), "{}{}", r.stdout, r.stderr);
        let check = r.stdout.split("(check it with `").nth(1).and_then(|t| t.split('`').next()).unwrap_or_else(|| {
            panic!("no check printed: {}", r.stdout);
        });
        let argv: Vec<&str> = check.split(' ').collect();
        assert_eq!(argv[0], "gcl", "{check}");
        let v = gcl(&argv[1..]);
        assert_eq!(v.code, Some(0), "`{check}`: {}{}", v.stdout, v.stderr);
        let want = if signed { "intact, signed by the trusted key" } else { "intact, unsigned" };
        assert!(v.stdout.contains(want), "`{check}`: {}", v.stdout);
    }
}
