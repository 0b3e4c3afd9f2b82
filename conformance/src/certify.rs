//! Certificate bundles: what `gcl certify` leaves a firmware team to keep, and the checks
//! behind `gcl certify --verify`.
//!
//! A bundle is a folder: `certificate.json` (firmware VERS text, profile, suite hash,
//! harness version, date, the options that changed what ran, a verdict per clause and one
//! for the run), the reports, one actual transcript per case under `transcripts/`, and
//! `MANIFEST.sha256`, which lists the SHA-256 of every other file in the `sha256sum` format,
//! so `sha256sum -c MANIFEST.sha256` checks it too.
//!
//! A manifest only proves that nothing changed since somebody wrote it: anybody can edit a
//! certificate and rerun `sha256sum`. So a bundle is signed: `MANIFEST.sig` holds an Ed25519
//! signature over the manifest (see [`SIGNATURE`] for its format) by a key pair that
//! [`generate_key`] makes, stored as PKCS#8 PEM (private) and SPKI PEM (public), the formats
//! `openssl genpkey -algorithm ed25519` and `openssl pkey -pubout` use. [`verify`] also
//! recomputes the certificate's verdicts from the bundled `report.json`, so a certificate
//! cannot disagree with the run it certifies.
//!
//! Verification checks the manifest, the signature, the certificate's verdict recomputed from the
//! bundled `report.json`, and a built-in profile claim against this gcl's built-in spec and suite
//! hash. Known failures (XFAIL) make a certificate partial and are listed in it (`excused`); a
//! certificate that drops them disagrees with its report. Only a `--pubkey` says who made a bundle:
//! without one the CLI says authenticity was not checked and exits 1 unless
//! `--allow-unverified`.

use std::collections::BTreeSet;
use std::io::Read;
use std::path::{Path, PathBuf};

use ed25519_dalek::pkcs8::spki::der::pem::LineEnding;
use ed25519_dalek::pkcs8::{DecodePrivateKey, DecodePublicKey, EncodePrivateKey, EncodePublicKey};
use ed25519_dalek::{Signature, Signer, SigningKey, Verifier, VerifyingKey};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::digest::hex;
/// The digest of a manifest line (kept here for callers that check a bundle by hand).
pub use crate::digest::sha256_hex;
use crate::report::{ProfileOrigin, ProfileSpec, RunOptions, RunReport, Verdict, write_all, write_atomic};
use gcl_host::files::{MAX_INPUT_BYTES, open_regular, read_limited, read_text_limited, too_large};

/// The size limit of a key file.
pub const MAX_KEY_BYTES: u64 = 64 << 10;

/// The manifest's file name.
pub const MANIFEST: &str = "MANIFEST.sha256";

/// The signature's file name. Its text is four lines:
///
/// ```text
/// gcl-signature 1
/// algorithm: ed25519
/// public-key: <32 bytes, hex>
/// signature: <64 bytes, hex>
/// ```
///
/// The signature is over [`SIGNED_PREFIX`] followed by the bytes of `MANIFEST.sha256`.
pub const SIGNATURE: &str = "MANIFEST.sig";

/// What is signed before the manifest's bytes, so a signature made for a bundle means
/// nothing anywhere else.
pub const SIGNED_PREFIX: &[u8] = b"gcl certificate manifest 1\n";

/// The largest file of a bundle `--verify` reads (reports with every transcript included).
pub const MAX_BUNDLE_FILE_BYTES: u64 = 256 << 20;

/// The certificate proper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Certificate {
    /// What the device answered to `VERS` (its lines).
    pub firmware_version: Vec<String>,
    /// The profile certified against: a built-in profile's id only when the spec that ran is
    /// that built-in's spec, else the file it came from, the id it declares and its hash (see
    /// [`ProfileSpec::label`]).
    pub profile: String,
    /// Where that spec came from and its hash; `--verify` checks that a built-in one is this
    /// gcl's built-in spec of that id, and that the suite hash is that spec's suite's.
    #[serde(default)]
    pub profile_spec: Option<ProfileSpec>,
    /// The target as given.
    pub target: String,
    /// The suite version: SHA-256 over every golden transcript.
    pub suite_hash: String,
    /// `gcl` and its version.
    pub harness_version: String,
    /// When the run started, RFC 3339 UTC.
    pub date: String,
    /// The levels run (MUST and SHOULD).
    pub levels: Vec<String>,
    /// `PASS` when every case of the levels ran and passed, `FAIL` when one did not;
    /// `PARTIAL: R of T cases` when only R of the T cases ran (or `--partial` was given) and
    /// those passed, `FAIL (PARTIAL: R of T cases)` when not. A known failure (XFAIL) narrows
    /// the certificate as a skip does: `PARTIAL: P of T cases passed, K known failures
    /// excused`; `ERROR (PARTIAL: ...)` when the hand stopped answering. The verdict line of the
    /// run's every output: [`RunReport::outcome`].
    pub verdict: String,
    /// Whether the certificate covers only part of the suite.
    pub partial: bool,
    /// Cases that ran (any verdict but SKIP).
    pub cases_run: usize,
    /// Cases of the levels certified in the suite.
    pub cases_total: usize,
    /// Every option that changed what ran.
    pub options: RunOptions,
    /// The cases whose failure was excused as a known failure (XFAIL): the certificate does
    /// not cover them.
    #[serde(default)]
    pub excused: Vec<String>,
    /// The verdict per spec clause.
    pub clauses: Vec<ClauseVerdict>,
}

/// One clause's verdict in a certificate.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ClauseVerdict {
    /// The clause.
    pub clause: String,
    /// The worst verdict among its cases.
    pub verdict: Verdict,
    /// How many cases check it.
    pub cases: usize,
}

/// The cases of a report whose failure a known-failures list excused (XFAIL).
pub fn excused_cases(report: &RunReport) -> Vec<String> {
    report.cases.iter().filter(|c| c.verdict == Verdict::Xfail).map(|c| c.id.clone()).collect()
}

impl Certificate {
    /// The certificate of a run whose report says what only certify knows
    /// ([`RunReport::certificate`]: the suite's size at the certified levels, the firmware's
    /// VERS) and whether the operator asked for part of the suite (`options.partial`).
    pub fn of_run(report: &RunReport) -> Certificate {
        let o = report.outcome();
        let facts = report.certificate.clone().unwrap_or_default();
        Certificate {
            firmware_version: facts.firmware_version,
            profile: report.profile_spec.as_ref().map_or_else(|| report.profile.clone(), ProfileSpec::label),
            profile_spec: report.profile_spec.clone(),
            target: report.target.clone(),
            suite_hash: report.suite_hash.clone(),
            harness_version: report.tool.clone(),
            date: report.started.clone(),
            levels: vec!["MUST".into(), "SHOULD".into()],
            verdict: o.verdict,
            partial: o.partial,
            cases_run: o.cases_run,
            cases_total: o.cases_total,
            options: RunOptions { partial: o.partial, ..report.options.clone() },
            excused: excused_cases(report),
            clauses: clause_verdicts(report),
        }
    }

    /// Whether the certificate says the hand passed the whole suite.
    pub fn is_pass(&self) -> bool {
        self.verdict == "PASS"
    }
}

fn clause_verdicts(report: &RunReport) -> Vec<ClauseVerdict> {
    report
        .clauses
        .iter()
        .map(|c| ClauseVerdict { clause: c.clause.clone(), verdict: c.verdict, cases: c.cases.len() })
        .collect()
}

/// Where the certificate disagrees with the report it was made from, or names a built-in
/// profile whose spec did not run; empty when it agrees.
pub fn disagreements(cert: &Certificate, report: &RunReport) -> Vec<String> {
    let mut out = Vec::new();
    let same = |out: &mut Vec<String>, what: &str, c: String, r: String| {
        if c != r {
            out.push(format!("the certificate's {what} `{c}` is not the report's `{r}`"));
        }
    };
    let o = report.outcome();
    let facts = report.certificate.clone().unwrap_or_default();
    let label = report.profile_spec.as_ref().map_or_else(|| report.profile.clone(), ProfileSpec::label);
    same(&mut out, "profile", cert.profile.clone(), label);
    same(&mut out, "target", cert.target.clone(), report.target.clone());
    same(&mut out, "suite hash", cert.suite_hash.clone(), report.suite_hash.clone());
    same(&mut out, "date", cert.date.clone(), report.started.clone());
    same(&mut out, "count of cases run", cert.cases_run.to_string(), o.cases_run.to_string());
    same(&mut out, "count of cases", cert.cases_total.to_string(), o.cases_total.to_string());
    same(&mut out, "firmware version", cert.firmware_version.join(" / "), facts.firmware_version.join(" / "));
    same(&mut out, "verdict", cert.verdict.clone(), o.verdict.clone());
    if !report.verdict.is_empty() {
        same(&mut out, "verdict (as report.json states it)", cert.verdict.clone(), report.verdict.clone());
    }
    same(&mut out, "partial", cert.partial.to_string(), o.partial.to_string());
    let excused = excused_cases(report);
    if cert.profile_spec != report.profile_spec {
        out.push("the certificate's profile spec is not the report's".to_string());
    }
    out.extend(builtin_disagreements(cert));
    if report.certificate.is_none() {
        out.push("report.json is not a certificate's report (it has no `certificate`)".to_string());
    }
    if !cert.partial {
        let certified = report.cases.iter().filter(|c| c.level == "MUST" || c.level == "SHOULD").count();
        same(&mut out, "count of cases", cert.cases_total.to_string(), certified.to_string());
        if cert.cases_run < cert.cases_total {
            out.push("a certificate that is not partial says cases did not run".to_string());
        }
    }
    if cert.excused != excused {
        out.push(format!(
            "the certificate excuses {} known failures, the report has {} (XFAIL)",
            cert.excused.len(),
            excused.len()
        ));
    }
    if !cert.partial && !excused.is_empty() {
        out.push("a certificate that is not partial excuses known failures".to_string());
    }
    let opts = RunOptions { partial: cert.partial, ..report.options.clone() };
    if cert.options != opts {
        out.push("the certificate's options are not the report's".to_string());
    }
    if cert.clauses != clause_verdicts(report) {
        out.push("the certificate's clause verdicts are not the report's".to_string());
    }
    let tally: usize = report.summary.values().sum();
    if tally != report.cases.len() {
        out.push(format!("report.json counts {tally} cases in its summary but lists {}", report.cases.len()));
    }
    let mut recount = report.clone();
    recount.tally();
    if recount.summary != report.summary || recount.clauses != report.clauses {
        out.push("report.json's summary or clauses do not follow from its cases".to_string());
    }
    out
}

/// A certificate that names a built-in profile must have run that built-in's spec, and its
/// suite hash must be that spec's suite's: checked when this gcl is the one that made the
/// certificate (another version's built-in profiles and suite may differ). A certificate
/// that names no spec at all is refused: nothing says what it certifies.
fn builtin_disagreements(cert: &Certificate) -> Vec<String> {
    let Some(spec) = &cert.profile_spec else {
        return vec!["the certificate does not say which profile spec ran (no `profile_spec`)".to_string()];
    };
    if spec.origin != ProfileOrigin::Builtin || cert.harness_version != format!("gcl {}", env!("CARGO_PKG_VERSION")) {
        return Vec::new();
    }
    let Ok(builtin) = gcl_model::Profile::builtin(&spec.name) else {
        return vec![format!("the certificate names a built-in profile `{}` that this gcl does not have", spec.name)];
    };
    let mut out = Vec::new();
    let ours = ProfileSpec::digest(&builtin);
    if spec.sha256 != ours || spec.id != builtin.id {
        out.push(format!(
            "the certificate names the built-in profile {}, but the spec that ran (sha256 {}) is not it (sha256 {ours})",
            spec.name, spec.sha256
        ));
    } else if cert.options.suite_dir.is_none()
        && let Ok(cases) = crate::suite::generate(&builtin)
    {
        let hash = crate::suite::suite_hash(&cases);
        if cert.suite_hash != hash {
            out.push(format!(
                "the certificate's suite hash {} is not that of the built-in profile {}'s suite ({hash})",
                cert.suite_hash, spec.name
            ));
        }
    }
    out
}

/// Writes a whole bundle into `dir` (created if needed; it should be empty), signed with
/// `key` when one is given.
pub fn write_bundle(
    dir: &Path,
    cert: &Certificate,
    report: &RunReport,
    transcripts: &[(String, String)],
    key: Option<&SigningKey>,
) -> std::io::Result<()> {
    std::fs::create_dir_all(dir.join("transcripts"))?;
    write_all(dir, report)?;
    for (id, text) in transcripts {
        write_atomic(&dir.join("transcripts").join(format!("{}.gcl", crate::report::safe_name(id))), text.as_bytes())?;
    }
    write_atomic(&dir.join("certificate.json"), &serde_json::to_vec_pretty(cert)?)?;
    let mut lines = String::new();
    for rel in files_under(dir)? {
        if rel == MANIFEST || rel == SIGNATURE {
            continue;
        }
        lines.push_str(&format!("{}  {}\n", hash_file(&dir.join(&rel))?, rel));
    }
    write_atomic(&dir.join(MANIFEST), lines.as_bytes())?;
    if let Some(key) = key {
        write_atomic(&dir.join(SIGNATURE), signature_text(key, lines.as_bytes()).as_bytes())?;
    }
    Ok(())
}

fn unhex(s: &str) -> Option<Vec<u8>> {
    if !s.len().is_multiple_of(2) || !s.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    (0..s.len()).step_by(2).map(|i| u8::from_str_radix(&s[i..i + 2], 16).ok()).collect()
}

fn signed_message(manifest: &[u8]) -> Vec<u8> {
    [SIGNED_PREFIX, manifest].concat()
}

fn signature_text(key: &SigningKey, manifest: &[u8]) -> String {
    let sig = key.sign(&signed_message(manifest));
    format!(
        "gcl-signature 1\nalgorithm: ed25519\npublic-key: {}\nsignature: {}\n",
        hex(key.verifying_key().as_bytes()),
        hex(&sig.to_bytes())
    )
}

fn parse_signature(text: &str) -> Result<(VerifyingKey, Signature), String> {
    let mut lines = text.lines();
    let mut field = |name: &str| -> Result<String, String> {
        let line = lines.next().ok_or_else(|| format!("{SIGNATURE}: missing `{name}` line"))?;
        line.strip_prefix(name).map(|v| v.trim().to_string()).ok_or_else(|| format!("{SIGNATURE}: expected `{name}`"))
    };
    if field("gcl-signature")? != "1" {
        return Err(format!("{SIGNATURE}: unknown format (expected `gcl-signature 1`)"));
    }
    if field("algorithm:")? != "ed25519" {
        return Err(format!("{SIGNATURE}: unknown algorithm (expected ed25519)"));
    }
    let key = unhex(&field("public-key:")?)
        .and_then(|b| <[u8; 32]>::try_from(b).ok())
        .and_then(|b| VerifyingKey::from_bytes(&b).ok())
        .ok_or_else(|| format!("{SIGNATURE}: bad public key"))?;
    let sig = unhex(&field("signature:")?)
        .and_then(|b| <[u8; 64]>::try_from(b).ok())
        .map(|b| Signature::from_bytes(&b))
        .ok_or_else(|| format!("{SIGNATURE}: bad signature"))?;
    Ok((key, sig))
}

/// A short name for a public key: the first 16 hex digits of the SHA-256 of its 32 bytes.
pub fn fingerprint(key: &VerifyingKey) -> String {
    sha256_hex(key.as_bytes())[..16].to_string()
}

/// Why a signing key could not be made, written or read.
#[derive(Debug, thiserror::Error)]
pub enum KeyError {
    /// The operating system gave no randomness for the key.
    #[error("no randomness from the operating system: {0}")]
    NoRandomness(String),
    /// The key could not be encoded as PEM.
    #[error("encoding the key: {0}")]
    Encode(String),
    /// A key file is already there; keys are never overwritten.
    #[error("{} exists; a key is never overwritten", .0.display())]
    Exists(PathBuf),
    /// A key file could not be written or read.
    #[error("{}: {error}", path.display())]
    Io {
        /// The key file.
        path: PathBuf,
        /// What failed.
        error: std::io::Error,
    },
    /// The file holds no key of the expected kind.
    #[error("{}: not {expected}: {detail}", path.display())]
    NotAKey {
        /// The key file.
        path: PathBuf,
        /// What kind of key was expected.
        expected: &'static str,
        /// The decoder's complaint.
        detail: String,
    },
}

/// Why [`verify`] could not look at a bundle at all (a usage or system error, unlike a
/// tampered bundle, which is a [`Tamper`]).
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    /// The path is not a folder.
    #[error("{}: no such directory (give the folder `gcl certify --out` wrote)", .0.display())]
    NotADirectory(PathBuf),
    /// The folder could not be listed.
    #[error("{}: {error}", path.display())]
    Unreadable {
        /// The folder.
        path: PathBuf,
        /// What failed.
        error: std::io::Error,
    },
}

/// Makes a key pair and writes the private key to `path` (PKCS#8 PEM, mode 0600; the file
/// must not exist) and the public key to `path` + `.pub` (SPKI PEM). Returns the public key.
pub fn generate_key(path: &Path) -> Result<VerifyingKey, KeyError> {
    use std::io::Write;
    use std::os::unix::fs::OpenOptionsExt;
    let mut seed = [0u8; 32];
    getrandom::fill(&mut seed).map_err(|e| KeyError::NoRandomness(e.to_string()))?;
    let key = SigningKey::from_bytes(&seed);
    let private = key.to_pkcs8_pem(LineEnding::LF).map_err(|e| KeyError::Encode(e.to_string()))?;
    let public = key.verifying_key().to_public_key_pem(LineEnding::LF).map_err(|e| KeyError::Encode(e.to_string()))?;
    let pub_path = public_key_path(path);
    for p in [path, pub_path.as_path()] {
        if p.exists() {
            return Err(KeyError::Exists(p.to_path_buf()));
        }
    }
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .open(path)
        .map_err(|error| KeyError::Io { path: path.to_path_buf(), error })?;
    f.write_all(private.as_bytes())
        .and_then(|()| f.sync_all())
        .map_err(|error| KeyError::Io { path: path.to_path_buf(), error })?;
    write_atomic(&pub_path, public.as_bytes()).map_err(|error| KeyError::Io { path: pub_path.clone(), error })?;
    Ok(key.verifying_key())
}

/// Where [`generate_key`] puts the public key of a private key file.
pub fn public_key_path(private: &Path) -> PathBuf {
    let mut s = private.as_os_str().to_os_string();
    s.push(".pub");
    PathBuf::from(s)
}

/// Reads a private key (PKCS#8 PEM, as [`generate_key`] or `openssl genpkey -algorithm
/// ed25519` writes it).
pub fn load_signing_key(path: &Path) -> Result<SigningKey, KeyError> {
    let text =
        read_text_limited(path, MAX_KEY_BYTES).map_err(|error| KeyError::Io { path: path.to_path_buf(), error })?;
    SigningKey::from_pkcs8_pem(&text).map_err(|e| KeyError::NotAKey {
        path: path.to_path_buf(),
        expected: "an Ed25519 private key in PKCS#8 PEM",
        detail: e.to_string(),
    })
}

/// Reads a public key (SPKI PEM, as [`generate_key`] or `openssl pkey -pubout` writes it).
pub fn load_verifying_key(path: &Path) -> Result<VerifyingKey, KeyError> {
    let text =
        read_text_limited(path, MAX_KEY_BYTES).map_err(|error| KeyError::Io { path: path.to_path_buf(), error })?;
    VerifyingKey::from_public_key_pem(&text).map_err(|e| KeyError::NotAKey {
        path: path.to_path_buf(),
        expected: "an Ed25519 public key in PEM",
        detail: e.to_string(),
    })
}

/// SHA-256 of a bundle's file, read as a stream (at most [`MAX_BUNDLE_FILE_BYTES`]).
fn hash_file(path: &Path) -> std::io::Result<String> {
    let mut f = open_regular(path)?.take(MAX_BUNDLE_FILE_BYTES + 1);
    let mut h = Sha256::new();
    let n = std::io::copy(&mut f, &mut h)?;
    if n > MAX_BUNDLE_FILE_BYTES {
        return Err(too_large(MAX_BUNDLE_FILE_BYTES));
    }
    Ok(hex(&h.finalize()))
}

/// Every file under `dir` that is not a directory, as `/`-separated relative paths, sorted.
fn files_under(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for e in std::fs::read_dir(dir.join(&rel))? {
            let e = e?;
            let r = rel.join(e.file_name());
            let ty = e.file_type()?;
            if ty.is_dir() {
                stack.push(r);
            } else {
                out.push(
                    r.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect::<Vec<_>>().join("/"),
                );
            }
        }
    }
    out.sort();
    Ok(out)
}

/// One problem `--verify` found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Tamper {
    /// A listed file's content changed.
    Modified(String),
    /// A listed file is gone.
    Missing(String),
    /// A file is in the bundle but not in the manifest.
    Unlisted(String),
    /// The manifest or the certificate does not parse.
    Malformed(String),
    /// The signature does not check, or is not by the trusted key, or is missing while a
    /// key was given.
    Signature(String),
    /// The certificate disagrees with the bundled report.
    Disagrees(String),
}

impl std::fmt::Display for Tamper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Tamper::Modified(p) => write!(f, "modified: {p}"),
            Tamper::Missing(p) => write!(f, "missing: {p}"),
            Tamper::Unlisted(p) => write!(f, "not in the manifest: {p}"),
            Tamper::Malformed(m) => write!(f, "malformed: {m}"),
            Tamper::Signature(m) => write!(f, "signature: {m}"),
            Tamper::Disagrees(m) => write!(f, "disagrees with report.json: {m}"),
        }
    }
}

/// Who signed an intact bundle.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Signed {
    /// No signature: the manifest holds, but anybody could have written it.
    Unsigned,
    /// Signed by the key given to check it.
    ByTrustedKey(VerifyingKey),
    /// Signed, and the signature checks, but no key was given to say whose key it is.
    ByUncheckedKey(VerifyingKey),
}

/// An intact bundle: its certificate and who signed it.
#[derive(Debug, Clone, PartialEq)]
pub struct Verified {
    /// The certificate.
    pub certificate: Certificate,
    /// The signature's status.
    pub signed: Signed,
}

/// Checks a bundle: its manifest, its signature (against `trusted` when given; a bundle
/// without one then fails) and that the certificate agrees with the bundled report.
/// `Ok(Ok(..))` when intact; `Ok(Err(problems))` otherwise; `Err` when `dir` is not a
/// bundle folder at all (a usage error).
pub fn verify(dir: &Path, trusted: Option<&VerifyingKey>) -> Result<Result<Verified, Vec<Tamper>>, BundleError> {
    if !dir.is_dir() {
        return Err(BundleError::NotADirectory(dir.to_path_buf()));
    }
    let manifest = match read_limited(&dir.join(MANIFEST), MAX_INPUT_BYTES) {
        Ok(m) => m,
        Err(e) => return Ok(Err(vec![Tamper::Malformed(format!("{MANIFEST}: {e}"))])),
    };
    let mut problems = Vec::new();
    let mut listed = BTreeSet::new();
    for (n, line) in String::from_utf8_lossy(&manifest).lines().enumerate() {
        let Some((hash, path)) = line.split_once("  ") else {
            problems.push(Tamper::Malformed(format!("{MANIFEST} line {}: expected `<sha256>  <path>`", n + 1)));
            continue;
        };
        if hash.len() != 64
            || !hash.bytes().all(|b| b.is_ascii_hexdigit())
            || path.contains("..")
            || path.starts_with('/')
        {
            problems.push(Tamper::Malformed(format!("{MANIFEST} line {}", n + 1)));
            continue;
        }
        listed.insert(path.to_string());
        match hash_file(&dir.join(path)) {
            Ok(h) if h == hash.to_ascii_lowercase() => {}
            Ok(_) => problems.push(Tamper::Modified(path.to_string())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => problems.push(Tamper::Missing(path.to_string())),
            Err(e) => problems.push(Tamper::Malformed(format!("{path}: {e}"))),
        }
    }
    for f in files_under(dir).map_err(|error| BundleError::Unreadable { path: dir.to_path_buf(), error })? {
        if f != MANIFEST && f != SIGNATURE && !listed.contains(&f) {
            problems.push(Tamper::Unlisted(f));
        }
    }
    for required in ["certificate.json", "report.json"] {
        if !listed.contains(required) && !problems.contains(&Tamper::Missing(required.into())) {
            problems.push(Tamper::Missing(required.into()));
        }
    }
    let signed = match read_limited(&dir.join(SIGNATURE), MAX_KEY_BYTES) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => match trusted {
            Some(_) => {
                problems
                    .push(Tamper::Signature(format!("the bundle is unsigned (no {SIGNATURE}), but a key was given")));
                Signed::Unsigned
            }
            None => Signed::Unsigned,
        },
        Err(e) => {
            problems.push(Tamper::Signature(format!("{SIGNATURE}: {e}")));
            Signed::Unsigned
        }
        Ok(bytes) => match parse_signature(&String::from_utf8_lossy(&bytes)) {
            Err(m) => {
                problems.push(Tamper::Signature(m));
                Signed::Unsigned
            }
            Ok((key, sig)) => {
                if key.verify(&signed_message(&manifest), &sig).is_err() {
                    problems.push(Tamper::Signature(format!(
                        "it does not match {MANIFEST} (signed by key {})",
                        fingerprint(&key)
                    )));
                }
                match trusted {
                    Some(t) if *t != key => {
                        problems.push(Tamper::Signature(format!(
                            "signed by key {}, not by the trusted key {}",
                            fingerprint(&key),
                            fingerprint(t)
                        )));
                        Signed::ByUncheckedKey(key)
                    }
                    Some(_) => Signed::ByTrustedKey(key),
                    None => Signed::ByUncheckedKey(key),
                }
            }
        },
    };
    if !problems.is_empty() {
        return Ok(Err(problems));
    }
    let parse = |name: &str| -> Result<serde_json::Value, Tamper> {
        let bytes = read_limited(&dir.join(name), MAX_BUNDLE_FILE_BYTES)
            .map_err(|e| Tamper::Malformed(format!("{name}: {e}")))?;
        serde_json::from_slice(&bytes).map_err(|e| Tamper::Malformed(format!("{name}: {e}")))
    };
    let typed = parse("certificate.json").and_then(|c| {
        serde_json::from_value::<Certificate>(c).map_err(|e| Tamper::Malformed(format!("certificate.json: {e}")))
    });
    let report = parse("report.json").and_then(|r| {
        serde_json::from_value::<RunReport>(r).map_err(|e| Tamper::Malformed(format!("report.json: {e}")))
    });
    let (certificate, report) = match (typed, report) {
        (Ok(c), Ok(r)) => (c, r),
        (c, r) => return Ok(Err(c.err().into_iter().chain(r.err()).collect())),
    };
    let mut differ = disagreements(&certificate, &report);
    // The page says who signed the bundle: it must be the key of MANIFEST.sig.
    let key = match &signed {
        Signed::Unsigned => None,
        Signed::ByTrustedKey(k) | Signed::ByUncheckedKey(k) => Some(fingerprint(k)),
    };
    let said = report.certificate.as_ref().and_then(|c| c.signed_by.clone());
    if said != key {
        differ.push(format!(
            "report.json says the bundle is signed by {}, but it is signed by {}",
            said.as_deref().unwrap_or("nobody"),
            key.as_deref().unwrap_or("nobody")
        ));
    }
    if !differ.is_empty() {
        return Ok(Err(differ.into_iter().map(Tamper::Disagrees).collect()));
    }
    Ok(Ok(Verified { certificate, signed }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sample report as certify leaves it: the built-in seed spec, its suite's hash, the
    /// certificate's facts.
    fn certified(mut report: RunReport, firmware: &[&str], total: usize) -> RunReport {
        let seed = gcl_model::Profile::builtin("seed").unwrap();
        report.kind = crate::report::ReportKind::Certify;
        report.level = "should".into();
        report.profile_spec = Some(ProfileSpec::of("seed", &seed));
        report.suite_hash = crate::suite::suite_hash(&crate::suite::generate(&seed).unwrap());
        report.certificate = Some(crate::report::CertificateFacts {
            cases_total: total,
            firmware_version: firmware.iter().map(|s| s.to_string()).collect(),
            signed_by: None,
        });
        report
    }

    fn bundle(key: Option<&SigningKey>) -> (tempfile::TempDir, Certificate) {
        let dir = tempfile::tempdir().unwrap();
        let mut report = certified(crate::report::tests::sample(), &["BarrettHand Firmware test"], 2);
        if let (Some(k), Some(c)) = (key, report.certificate.as_mut()) {
            c.signed_by = Some(fingerprint(&k.verifying_key()));
        }
        let cert = Certificate::of_run(&report);
        write_bundle(dir.path(), &cert, &report, &[("framing-echo".into(), "> HI\\r\n< HI\\n\\r=> \n".into())], key)
            .unwrap();
        (dir, cert)
    }

    /// What a forger does: rewrite the manifest as `sha256sum` would.
    fn rerun_sha256sum(dir: &Path) {
        let mut lines = String::new();
        for rel in files_under(dir).unwrap() {
            if rel != MANIFEST && rel != SIGNATURE {
                lines.push_str(&format!("{}  {}\n", sha256_hex(&std::fs::read(dir.join(&rel)).unwrap()), rel));
            }
        }
        std::fs::write(dir.join(MANIFEST), lines).unwrap();
    }

    fn key() -> SigningKey {
        SigningKey::from_bytes(&[7; 32])
    }

    #[test]
    fn an_untouched_bundle_verifies_and_says_it_is_unsigned() {
        let (dir, cert) = bundle(None);
        assert_eq!(cert.verdict, "FAIL");
        let v = verify(dir.path(), None).unwrap().unwrap();
        assert_eq!(v.certificate, cert);
        assert_eq!(v.signed, Signed::Unsigned);
        let manifest = std::fs::read_to_string(dir.path().join(MANIFEST)).unwrap();
        assert!(manifest.contains("  transcripts/framing-echo.gcl\n"));
        assert!(manifest.contains("  certificate.json\n"));
    }

    #[test]
    fn tampering_is_found() {
        let (dir, _) = bundle(None);
        let p = dir.path().join("certificate.json");
        let text = std::fs::read_to_string(&p).unwrap().replace("\"FAIL\"", "\"PASS\"");
        std::fs::write(&p, text).unwrap();
        std::fs::remove_file(dir.path().join("junit.xml")).unwrap();
        std::fs::write(dir.path().join("transcripts/extra.gcl"), "x").unwrap();
        let problems = verify(dir.path(), None).unwrap().unwrap_err();
        assert!(problems.contains(&Tamper::Modified("certificate.json".into())), "{problems:?}");
        assert!(problems.contains(&Tamper::Missing("junit.xml".into())), "{problems:?}");
        assert!(problems.contains(&Tamper::Unlisted("transcripts/extra.gcl".into())), "{problems:?}");
    }

    #[test]
    fn a_forged_verdict_with_a_rewritten_manifest_disagrees_with_the_report() {
        let (dir, _) = bundle(None);
        let p = dir.path().join("certificate.json");
        let text = std::fs::read_to_string(&p).unwrap().replace("\"verdict\": \"FAIL\"", "\"verdict\": \"PASS\"");
        assert!(text.contains("\"verdict\": \"PASS\""));
        std::fs::write(&p, text).unwrap();
        rerun_sha256sum(dir.path());
        let problems = verify(dir.path(), None).unwrap().unwrap_err();
        assert!(
            problems.iter().any(|p| matches!(p, Tamper::Disagrees(m) if m.contains("verdict `PASS`"))),
            "{problems:?}"
        );
    }

    #[test]
    fn signatures_are_checked_against_the_trusted_key() {
        let k = key();
        let (dir, _) = bundle(Some(&k));
        let v = verify(dir.path(), Some(&k.verifying_key())).unwrap().unwrap();
        assert_eq!(v.signed, Signed::ByTrustedKey(k.verifying_key()));
        assert_eq!(verify(dir.path(), None).unwrap().unwrap().signed, Signed::ByUncheckedKey(k.verifying_key()));
        // Another key is not trusted.
        let other = SigningKey::from_bytes(&[8; 32]).verifying_key();
        let problems = verify(dir.path(), Some(&other)).unwrap().unwrap_err();
        assert!(problems.iter().any(|p| matches!(p, Tamper::Signature(m) if m.contains("not by the trusted key"))));
        // A forger who rewrites the report and the manifest consistently breaks the signature.
        let r = dir.path().join("report.json");
        let text = std::fs::read_to_string(&r).unwrap().replace("\"duration_ms\": 12.5", "\"duration_ms\": 13.5");
        std::fs::write(&r, text).unwrap();
        rerun_sha256sum(dir.path());
        let problems = verify(dir.path(), Some(&k.verifying_key())).unwrap().unwrap_err();
        assert!(problems.iter().any(|p| matches!(p, Tamper::Signature(m) if m.contains("does not match"))));
        // An unsigned bundle fails when a key is given.
        let (unsigned, _) = bundle(None);
        let problems = verify(unsigned.path(), Some(&k.verifying_key())).unwrap().unwrap_err();
        assert!(problems.iter().any(|p| matches!(p, Tamper::Signature(m) if m.contains("unsigned"))));
    }

    /// Issue 20 item 1: a run whose failures were all known failures is no PASS; the
    /// certificate is partial and names the excused cases, and a forger who drops them from
    /// the certificate is found.
    #[test]
    fn known_failures_narrow_a_certificate() {
        let mut r = crate::report::tests::sample();
        for c in &mut r.cases {
            if c.verdict.fails_run() {
                c.verdict = Verdict::Xfail;
            }
        }
        r.tally();
        let n = r.cases.len();
        let r = certified(r, &[], n);
        let xfail: Vec<String> = r.cases.iter().filter(|c| c.verdict == Verdict::Xfail).map(|c| c.id.clone()).collect();
        assert!(!xfail.is_empty() && r.passed());
        let cert = Certificate::of_run(&r);
        assert!(cert.partial && !cert.is_pass(), "{}", cert.verdict);
        assert!(cert.verdict.contains("known failures excused"), "{}", cert.verdict);
        assert_eq!(cert.excused, xfail);
        assert!(disagreements(&cert, &r).is_empty(), "{:?}", disagreements(&cert, &r));
        let forged = Certificate { verdict: "PASS".into(), partial: false, excused: vec![], ..cert.clone() };
        let found = disagreements(&forged, &r);
        assert!(found.iter().any(|m| m.contains("excuses 0 known failures")), "{found:?}");
    }

    #[test]
    fn a_missing_folder_is_a_usage_error_not_tampering() {
        let dir = tempfile::tempdir().unwrap();
        assert!(verify(&dir.path().join("nonesuch"), None).is_err());
    }

    #[test]
    fn generated_keys_load_back_and_are_never_overwritten() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("gcl-key.pem");
        let public = generate_key(&p).unwrap();
        let private = load_signing_key(&p).unwrap();
        assert_eq!(private.verifying_key(), public);
        assert_eq!(load_verifying_key(&public_key_path(&p)).unwrap(), public);
        assert!(std::fs::read_to_string(&p).unwrap().starts_with("-----BEGIN PRIVATE KEY-----"));
        use std::os::unix::fs::PermissionsExt;
        assert_eq!(std::fs::metadata(&p).unwrap().permissions().mode() & 0o077, 0, "private key readable by others");
        assert!(generate_key(&p).is_err());
        assert!(load_verifying_key(&p).is_err(), "a private key is not a public key");
    }

    #[test]
    fn partial_verdicts_say_so() {
        use crate::report::verdict_line;
        assert_eq!(verdict_line(true, false, false, 336, 336, 0), "PASS");
        assert_eq!(verdict_line(true, false, true, 12, 336, 0), "PARTIAL: 12 of 336 cases");
        assert_eq!(verdict_line(false, false, true, 12, 336, 0), "FAIL (PARTIAL: 12 of 336 cases)");
        assert_eq!(verdict_line(false, true, true, 12, 336, 0), "ERROR (PARTIAL: 12 of 336 cases)");
        assert_eq!(
            verdict_line(true, false, false, 216, 216, 125),
            "PARTIAL: 91 of 216 cases passed, 125 known failures excused"
        );
        let mut r = crate::report::tests::sample();
        for c in &mut r.cases {
            c.verdict = Verdict::Skip;
        }
        r.tally();
        let r = certified(r, &[], 2);
        let c = Certificate::of_run(&r);
        assert!(c.partial && !c.is_pass(), "nothing ran: not a PASS");
        assert_eq!(c.verdict, "FAIL (PARTIAL: 0 of 2 cases)");
    }
}
