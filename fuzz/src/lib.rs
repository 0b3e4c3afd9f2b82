//! Fuzz entry points for gcl. Each takes arbitrary bytes and must never panic.
//!
//! A panic here is a finding, and its message says which kind:
//! - the model panicked: an architecture invariant is broken (no input from a device, a host,
//!   a file or a fuzzer may panic the model);
//! - a property this crate checks does not hold (`grammar round trip: ...`,
//!   `device output unbounded: ...`, ...).
//!
//! The cargo-fuzz targets in `fuzz_targets/` are thin wrappers over these functions, and the
//! crate's tests run every function over the seed corpora in `seeds/` on stable, so the fuzz
//! logic is built and exercised by `cargo test` like any other code. This crate owns no model
//! logic: it only feeds the model and checks what comes out.
//!
//! Besides the model's own entry points (`grammar`, `device`, `realtime`, `spec`), `wire` is
//! `gcl fuzz device`'s generator and oracle against the in-process sim with a fault,
//! `transcript` the transcript reader's round trip, and `client` the host client core against
//! any bytes. The `device` input's fault mask is 64 bits, one per fault, checked at compile
//! time. `run-ci.sh` runs each target for a bounded time with `RUSTC_BOOTSTRAP=1`.

pub mod replay;
pub mod seeds;

use std::sync::{Arc, OnceLock};
use std::time::Duration;

use gcl_model::device::{Device, DeviceConfig, Fault, Mode, Scenario};
use gcl_model::escape::escape;
use gcl_model::grammar::{Line, ParseOptions, parse_line, parse_line_with};
use gcl_model::motor::MotorSet;
use gcl_model::params::ParamStore;
use gcl_model::realtime::{self, BlockError, BlockLayout, RtLayout};
use gcl_model::spec::{BlockKind, Profile, embedded};
use gcl_model::status::StatusBits;

/// A fuzz entry point: arbitrary bytes in, a panic only on a finding.
pub type EntryPoint = fn(&[u8]);

/// Every entry point, by the name of its cargo-fuzz target and seed directory.
pub const TARGETS: &[(&str, EntryPoint)] = &[
    ("grammar", grammar),
    ("device", |data| {
        device(data);
    }),
    ("realtime", realtime),
    ("wire", wire),
    ("transcript", transcript),
    ("client", client),
    ("spec", |data| {
        spec(data);
    }),
];

/// The most output one command line, one RealTime header or one finished command may cause
/// (the longest is `A?` or a `...LISTAV`, a few KiB). The `device` target holds every step's
/// output to this much per byte it fed in, plus what the input queue can hold.
pub const MAX_RESPONSE: usize = 16 * 1024;

/// Simulated time one `device` input may spend; physics costs one step per millisecond while
/// something moves, so this bounds the work of one input.
pub const DEVICE_TIME_BUDGET: Duration = Duration::from_secs(60);

/// The name the `spec` target gives the fuzzed file; its includes resolve to the embedded
/// files (and to itself, to reach the include-cycle check).
pub const SPEC_FILE_NAME: &str = "fuzz.toml";

/// The embedded profiles, loaded once.
pub fn builtin_profiles() -> &'static [Arc<Profile>] {
    static ALL: OnceLock<Vec<Arc<Profile>>> = OnceLock::new();
    ALL.get_or_init(|| Profile::builtin_names().map(|n| Profile::builtin(n).expect("embedded profiles load")).collect())
}

// ---------------------------------------------------------------------------------- grammar

/// `parse_line` on every embedded profile, for each CR-separated piece of `data`.
///
/// Checks, besides not panicking: an accepted command prints (`Command::to_line`) a line that
/// parses back to the same command; `Line::Empty` is exactly a line of separators; a rejection
/// carries at least one problem and its status is the OR of the problems' bits; the
/// case-sensitive grammar (a fault) accepts nothing the protocol's grammar refuses.
pub fn grammar(data: &[u8]) {
    for profile in builtin_profiles() {
        for line in data.split(|b| *b == profile.framing.terminator) {
            check_line(profile, line);
        }
    }
}

fn check_line(profile: &Profile, line: &[u8]) {
    let parsed = parse_line(profile, line);
    match &parsed {
        Ok(Line::Empty) => assert!(
            line.iter().all(|b| matches!(b, b' ' | b'\t' | b'\n')),
            "grammar: `{}` parsed as an empty line ({})",
            escape(line),
            profile.id
        ),
        Ok(Line::Command(c)) => {
            let text = c.to_line(profile);
            let again = parse_line(profile, text.as_bytes());
            assert!(
                matches!(&again, Ok(Line::Command(c2)) if c2 == c),
                "grammar round trip ({}): `{}` parsed as {c:?}, printed as `{text}`, which parses as {again:?}",
                profile.id,
                escape(line)
            );
        }
        Err(r) => {
            assert!(!r.problems.is_empty(), "grammar: `{}` rejected with no problem", escape(line));
            let bits = r.problems.iter().fold(StatusBits::empty(), |s, p| s | p.status());
            assert_eq!(r.status, bits, "grammar: `{}`: status is not the OR of its problems", escape(line));
        }
    }
    let strict =
        parse_line_with(profile, line, ParseOptions { case_sensitive_commands: true, ..ParseOptions::default() });
    if let Ok(s) = &strict {
        assert_eq!(
            parsed.as_ref().ok(),
            Some(s),
            "grammar ({}): `{}`: the case-sensitive grammar accepts what the protocol's does not",
            profile.id,
            escape(line)
        );
    }
}

// ---------------------------------------------------------------------------------- device

/// How long a `device` step waits before its bytes arrive, decoded from one byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// Let this much time pass (`handle_timeout` semantics when no bytes follow).
    For(Duration),
    /// `run_until_idle` with this limit first; the bytes arrive when it returns.
    UntilIdle(Duration),
}

impl Wait {
    /// Decodes a wait byte: `0..=63` ms, `64..=127` steps of 50 ms, `128..=191` seconds,
    /// `192..=255` run until idle for at most 1..=64 s.
    pub fn from_byte(b: u8) -> Wait {
        let n = u64::from(b & 63);
        match b >> 6 {
            0 => Wait::For(Duration::from_millis(n)),
            1 => Wait::For(Duration::from_millis(50 * n)),
            2 => Wait::For(Duration::from_secs(n)),
            _ => Wait::UntilIdle(Duration::from_secs(n + 1)),
        }
    }
}

/// One step of a `device` session: wait, then feed bytes (or only let time pass).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Step {
    /// The wait byte (see [`Wait::from_byte`]).
    pub wait: u8,
    /// The bytes fed after the wait, at most 255.
    pub bytes: Vec<u8>,
}

// Every fault has a bit in `DeviceSession::faults`.
const _: () = assert!(Fault::ALL.len() <= u64::BITS as usize);

/// What the `device` target reads from its input bytes.
///
/// Layout: `profile`, `faults` (eight bytes, little-endian, bit `i` = `Fault::ALL[i]`, so
/// every fault is reachable),
/// `scenario` (bit flags, see [`scenario_of`]), then steps, each `wait`, `len`, `len` bytes.
/// Missing bytes read as zero, a short last chunk is kept as it is: every input is a session.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DeviceSession {
    /// Index into the embedded profiles, modulo their number.
    pub profile: u8,
    /// Deliberate faults to switch on, bit `i` for `Fault::ALL[i]`.
    pub faults: u64,
    /// Scenario flags, also the noise seed.
    pub scenario: u8,
    /// The steps.
    pub steps: Vec<Step>,
}

impl DeviceSession {
    /// Reads a session from fuzzer bytes. Never fails.
    pub fn from_bytes(data: &[u8]) -> DeviceSession {
        let at = |i: usize| data.get(i).copied().unwrap_or(0);
        let mut s = DeviceSession {
            profile: at(0),
            faults: u64::from_le_bytes(std::array::from_fn(|i| at(1 + i))),
            scenario: at(9),
            steps: vec![],
        };
        let mut rest = data.get(10..).unwrap_or(&[]);
        while let [wait, tail @ ..] = rest {
            let (len, tail) = match tail {
                [len, tail @ ..] => (usize::from(*len), tail),
                [] => (0, tail),
            };
            let n = len.min(tail.len());
            s.steps.push(Step { wait: *wait, bytes: tail[..n].to_vec() });
            rest = &tail[n..];
        }
        s
    }

    /// The bytes [`DeviceSession::from_bytes`] reads back as `self` (chunks over 255 bytes
    /// are split into steps that arrive at once).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = vec![self.profile];
        out.extend_from_slice(&self.faults.to_le_bytes());
        out.push(self.scenario);
        for step in &self.steps {
            let mut chunks = step.bytes.chunks(255);
            let first = chunks.next().unwrap_or(&[]);
            for (wait, chunk) in std::iter::once((step.wait, first)).chain(chunks.map(|c| (0, c))) {
                out.push(wait);
                out.push(chunk.len() as u8);
                out.extend_from_slice(chunk);
            }
        }
        out
    }
}

/// The scenario a `device` session's flag byte stands for: bit 0 an object in F1's way,
/// bit 1 objects for the other motors, bit 2 a hot hand, bit 3 no noise, bit 4 and bit 7
/// unusual power-up positions (bit 7 outside the joint stops), bit 5 analog inputs, bit 6
/// an object at F1's open stop.
pub fn scenario_of(bits: u8) -> Scenario {
    let mut s = Scenario::default();
    let on = |i: u8| bits & (1 << i) != 0;
    if on(0) {
        s.objects[0] = Some(4000);
    }
    if on(1) {
        s.objects[1] = Some(6000);
        s.objects[2] = Some(9000);
        s.objects[3] = Some(1000);
    }
    if on(2) {
        s.temperature = 900;
    }
    if on(3) {
        s.temperature_noise = 0;
        s.strain_noise = 0;
    }
    if on(4) {
        s.initial_positions = [5000, 100, 17000, 3000];
    }
    if on(5) {
        s.analog_input = [0, 255, 1023, 65535];
    }
    if on(6) {
        s.objects[0] = Some(0);
    }
    if on(7) {
        s.initial_positions = [-500, 20000, 0, 4000];
    }
    s
}

/// Feeds a session of timed byte chunks to a `Device` of the profile the first byte picks.
///
/// Checks, besides not panicking: each step's output is at most [`MAX_RESPONSE`] per byte fed
/// in (plus what the input queue held); the device's clock is where the host put it;
/// `run_until_idle` stays within its limit; the device is in RealTime mode exactly when it has
/// a RealTime layout, and asks for a timeout exactly when a command is running.
pub fn device(data: &[u8]) -> DeviceRun {
    let session = DeviceSession::from_bytes(data);
    let profiles = builtin_profiles();
    let profile = profiles[usize::from(session.profile) % profiles.len()].clone();
    let faults =
        Fault::ALL.iter().enumerate().filter(|(i, _)| session.faults & (1 << i) != 0).map(|(_, f)| *f).collect();
    let config = DeviceConfig {
        seed: u64::from(session.scenario),
        scenario: scenario_of(session.scenario),
        faults,
        ..DeviceConfig::default()
    };
    let mut hand = Device::new(profile.clone(), config);
    let mut run = DeviceRun::default();
    let banner = hand.take_output();
    assert!(banner.len() <= MAX_RESPONSE, "device: banner of {} bytes", banner.len());
    let queue_cap = 2 * profile.framing.max_line + 4;
    let mut budget = DEVICE_TIME_BUDGET;
    let mut now = Duration::ZERO;
    for (n, step) in session.steps.iter().enumerate() {
        match Wait::from_byte(step.wait) {
            Wait::For(gap) => {
                let gap = gap.min(budget);
                budget -= gap;
                now += gap;
            }
            Wait::UntilIdle(limit) => {
                let limit = limit.min(budget);
                let start = hand.now();
                let end = hand.run_until_idle(limit);
                assert!(
                    start <= end && end <= start + limit,
                    "device: run_until_idle({limit:?}) from {start:?} returned {end:?}"
                );
                budget -= end - start;
                now = now.max(end);
            }
        }
        if step.bytes.is_empty() {
            hand.handle_timeout(now);
        } else {
            hand.handle_input(now, &step.bytes);
        }
        assert_eq!(hand.now(), now, "device: step {n}: the hand's clock is not the host's");
        let out = hand.take_output();
        let bound = (step.bytes.len() + queue_cap + 1) * MAX_RESPONSE;
        assert!(
            out.len() <= bound,
            "device output unbounded: step {n} fed {} bytes and got {} bytes back",
            step.bytes.len(),
            out.len()
        );
        let mode = hand.mode();
        run.output += out.len();
        if !run.modes.contains(&mode) {
            run.modes.push(mode);
        }
        assert_eq!(
            mode == Mode::Loop,
            hand.rt_layout().is_some(),
            "device: step {n}: mode {mode:?} but RealTime layout {:?}",
            hand.rt_layout().map(|l| l.motors())
        );
        assert_eq!(
            mode == Mode::Busy,
            hand.poll_timeout().is_some(),
            "device: step {n}: mode {mode:?} but poll_timeout {:?}",
            hand.poll_timeout()
        );
        // Public accessors on every state.
        for m in gcl_model::Motor::ALL {
            let _ = (hand.position(m), hand.initialized(m));
        }
        let _ = (hand.last_status().code(), hand.baud(), hand.nv().writes);
    }
    run
}

/// What a `device` run went through, for tests that check a seed reaches what it is for.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DeviceRun {
    /// The modes the hand was in after some step, in the order first seen.
    pub modes: Vec<Mode>,
    /// Bytes of output after the banner.
    pub output: usize,
}

// ---------------------------------------------------------------------------------- realtime

/// RealTime layouts from arbitrary flags and motor sets, decoding arbitrary bytes, and
/// encode/decode round trips, plus the LFDP and LCV arithmetic.
///
/// Layout: `profile`, `motors` (low four bits), `flags` (two bytes, little-endian, bit `i` for
/// the `i`-th RealTime flag of the profile in listing order), then free bytes used as a block
/// to decode, as values to encode (eight bytes each, little-endian) and as LFDP operands.
///
/// Checks: fields sit back to back after the header and belong to the loop's motors; a block
/// of the right size decodes exactly when its header is valid, and re-encodes to the same
/// bytes; clamped encoding decodes to the clamped values; checked encoding succeeds exactly
/// when every value fits; an LFDP step sends a byte and moves the reported position by it.
pub fn realtime(data: &[u8]) {
    let at = |i: usize| data.get(i).copied().unwrap_or(0);
    let profiles = builtin_profiles();
    let profile = &profiles[usize::from(at(0)) % profiles.len()];
    let motors = MotorSet::from_bits(at(1));
    let flags = u16::from_le_bytes([at(2), at(3)]);
    let rest = data.get(4..).unwrap_or(&[]);

    let mut store = ParamStore::defaults(profile);
    let rt_params: Vec<_> = profile.param_ids().filter(|id| profile.param(*id).rt.is_some()).collect();
    for (i, id) in rt_params.iter().enumerate() {
        let on = i < 16 && flags & (1 << i) != 0;
        store.set_unchecked(profile, *id, MotorSet::ALL, i64::from(on));
    }
    let layout = RtLayout::compute(profile, &store, motors);
    assert_eq!(layout.motors(), motors);
    for block in [layout.control(), layout.feedback()] {
        check_block_layout(block, motors);
        check_block_codec(block, rest);
    }
    let lcv_bits = profile.hand.lcv_fraction_bits;
    for (i, pair) in rest.chunks(2).take(8).enumerate() {
        let datum = i64::from(pair[0] as i8);
        let lcvc = i64::from(*pair.get(1).unwrap_or(&1));
        for bits in [lcv_bits, lcv_bits + 4] {
            let v = realtime::control_velocity(datum, lcvc, bits);
            assert!(v.is_finite(), "realtime: LCV {datum} × {lcvc} >> {bits} (pair {i}) is {v}");
        }
    }
    for quad in rest.chunks_exact(9).take(8) {
        let reported = i64::from(i32::from_le_bytes([quad[0], quad[1], quad[2], quad[3]]));
        let present = i64::from(i32::from_le_bytes([quad[4], quad[5], quad[6], quad[7]]));
        check_lfdp(reported, present, i64::from(quad[8] >> 1), quad[8] & 1 != 0);
    }
}

fn check_block_layout(block: &BlockLayout, motors: MotorSet) {
    let mut offset = 1;
    for f in block.fields() {
        assert_eq!(f.offset(), offset, "realtime: field {} of motor {:?} is not back to back", f.name(), f.motor());
        assert!(f.size() == 1 || f.size() == 2, "realtime: field {} is {} bytes", f.name(), f.size());
        assert!(f.motor().is_none_or(|m| motors.contains(m)), "realtime: field {} of motor {:?}", f.name(), f.motor());
        offset += f.size();
    }
    assert_eq!(
        block.size(),
        offset,
        "realtime: {:?} block size {} for fields ending at {offset}",
        block.kind(),
        block.size()
    );
}

fn check_block_codec(block: &BlockLayout, bytes: &[u8]) {
    let header_ok = |h: u8| match block.kind() {
        BlockKind::Feedback => h == realtime::FEEDBACK_HEADER,
        BlockKind::Control => h == b'C' || h == b'c',
    };
    // Whatever the length.
    let whole = block.decode(bytes);
    assert_eq!(
        whole.is_ok(),
        bytes.len() == block.size() && header_ok(bytes[0]),
        "realtime: decode of {} bytes",
        bytes.len()
    );
    if let Some(candidate) = bytes.get(..block.size()) {
        match block.decode(candidate) {
            Ok((h, values)) => {
                assert!(header_ok(h));
                let mut again = Vec::new();
                block.encode(h, &values, &mut again).expect("decoded values fit their fields");
                assert_eq!(again, candidate, "realtime: decode then encode changed the block");
            }
            Err(_) => assert!(!header_ok(candidate[0]), "realtime: a block with a valid header did not decode"),
        }
    }
    let values: Vec<i64> = bytes
        .chunks(8)
        .map(|c| {
            let mut b = [0u8; 8];
            b[..c.len()].copy_from_slice(c);
            i64::from_le_bytes(b)
        })
        .chain(std::iter::repeat(0))
        .take(block.fields().len())
        .collect();
    let header = match block.kind() {
        BlockKind::Feedback => realtime::FEEDBACK_HEADER,
        BlockKind::Control => b'C',
    };
    let mut clamped = Vec::new();
    block.encode_clamped(header, &values, &mut clamped);
    assert_eq!(clamped.len(), block.size());
    let (h, decoded) = block.decode(&clamped).expect("an encoded block decodes");
    assert_eq!(h, header);
    for ((f, v), d) in block.fields().iter().zip(&values).zip(&decoded) {
        assert_eq!(
            *d,
            (*v).clamp(f.min(), f.max()),
            "realtime: field {} of motor {:?} round trip",
            f.name(),
            f.motor()
        );
    }
    let fits = block.fields().iter().zip(&values).all(|(f, v)| (f.min()..=f.max()).contains(v));
    let mut checked = Vec::new();
    match block.encode(header, &values, &mut checked) {
        Ok(()) => assert!(fits && checked == clamped, "realtime: checked encode accepted a value that does not fit"),
        Err(e) => assert!(!fits, "realtime: checked encode refused values that fit: {e}"),
    }
    if let Some((_, fewer)) = values.split_last() {
        let r = block.encode(header, fewer, &mut checked);
        assert!(matches!(r, Err(BlockError::Arity { .. })), "realtime: encode of too few values gave {r:?}");
    }
}

fn check_lfdp(reported: i64, present: i64, coeff: i64, discard: bool) {
    let c = coeff.max(1);
    let mut r = reported;
    let sent = realtime::lfdp_step(&mut r, present, coeff, discard);
    let moved = r - reported;
    if discard {
        assert_eq!(moved, (present - reported) / c * c, "realtime: LFDP discard moved the reported position wrongly");
    } else {
        assert_eq!(moved, i64::from(sent) * c, "realtime: LFDP moved the reported position by other than sent × LFDPC");
        // Carrying the rest, the reported position reaches the present one within LFDPC.
        let steps = (present - reported).abs() / (127 * c) + 2;
        if steps < 1000 {
            for _ in 0..steps {
                realtime::lfdp_step(&mut r, present, coeff, false);
            }
            assert!(
                (present - r).abs() < c,
                "realtime: LFDP from {reported} stuck at {r}, present {present}, LFDPC {c}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------- spec

/// Arbitrary text as a top-level spec file ([`SPEC_FILE_NAME`]; includes resolve to the
/// embedded files). `Profile::load_with` must return a profile or a typed error; a profile it
/// returns must run: a hand of it goes through a fixed session (HI, every command, every
/// parameter read and written at its limits, a RealTime loop with every flag) without
/// panicking. A profile is data, so nothing in it may panic the model.
///
/// Returns whether the text loaded as a profile.
pub fn spec(data: &[u8]) -> bool {
    let text = String::from_utf8_lossy(data);
    let resolve = |f: &str| if f == SPEC_FILE_NAME { Some(text.to_string()) } else { embedded(f).map(str::to_string) };
    match Profile::load_with(SPEC_FILE_NAME, &resolve) {
        Ok(profile) => {
            exercise(Arc::new(profile));
            true
        }
        Err(e) => {
            let _ = e.to_string();
            false
        }
    }
}

/// The fixed session the `spec` target runs on a profile that loaded.
pub fn exercise(profile: Arc<Profile>) {
    let mut hand = Device::with_profile(profile.clone());
    // Simulated time for each phase (physics costs a step per ms while something moves).
    const PHASE: Duration = Duration::from_secs(10);
    let budget = std::cell::Cell::new(PHASE);
    let framing = &profile.framing;
    let (cr, abort) = (framing.terminator, framing.abort);
    let send = |hand: &mut Device, bytes: &[u8]| {
        let now = hand.now();
        hand.handle_input(now, bytes);
        let limit = Duration::from_secs(3).min(budget.get());
        let end = hand.run_until_idle(limit);
        budget.set(budget.get().saturating_sub(end - now));
        if hand.mode() != Mode::Idle {
            let now = hand.now();
            hand.handle_input(now, &[abort]);
        }
        // What a transport asks after each exchange.
        let _ = (hand.baud(), hand.last_status(), hand.poll_timeout());
        let out = hand.take_output();
        assert!(out.len() <= 64 * MAX_RESPONSE, "spec: {} bytes for `{}`", out.len(), escape(bytes));
    };
    let line = |text: &str| [text.as_bytes(), &[cr]].concat();
    send(&mut hand, &line("HI"));
    let prefix = profile.prefixes.first().map(|p| p.char.to_string()).unwrap_or_default();
    for c in &profile.commands {
        send(&mut hand, &line(&c.name));
        send(&mut hand, &line(&format!("{prefix}{} 1", c.name)));
        send(&mut hand, &line(&format!("?{}", c.name)));
    }
    send(&mut hand, &line("HI"));
    for id in profile.param_ids() {
        let p = profile.param(id);
        send(&mut hand, &line(&format!("{} {}", profile.getter(id), p.name)));
        let setter = profile.setter(id);
        for v in [p.min, p.max, p.default.unwrap_or(p.min)].into_iter().chain(p.values.iter().flatten().copied()) {
            send(&mut hand, &line(&format!("{setter} {} {v}", p.name)));
        }
        if p.rt.is_some() {
            send(&mut hand, &line(&format!("{setter} {} 1", p.name)));
        }
    }
    // Every writable parameter at its top, then at its bottom: HI, motion, a RealTime loop
    // with every flag on, on every motor (the prefix of every prefix character).
    let all: String = profile.prefixes.iter().map(|p| p.char).collect();
    for top in [true, false] {
        budget.set(PHASE);
        for id in profile.param_ids() {
            let p = profile.param(id);
            let v = match (&p.values, top) {
                (Some(vs), true) => vs.iter().max().copied(),
                (Some(vs), false) => vs.iter().min().copied(),
                (None, true) => Some(p.max),
                (None, false) => Some(p.min),
            };
            let v = if p.rt.is_some() && profile.value_ok(id, 1) { Some(1) } else { v };
            if let Some(v) = v {
                send(&mut hand, &line(&format!("{} {} {v}", profile.setter(id), p.name)));
            }
        }
        for cmd in ["HI", "C", "O", "M", "TC", "TO", "HI"] {
            send(&mut hand, &line(&format!("{all}{cmd}")));
        }
        let now = hand.now();
        hand.handle_input(now, &line(&format!("{all}LOOP")));
        if let Some(layout) = hand.rt_layout().cloned() {
            let data = |b: u8| vec![b; layout.control().data_len()];
            let mut t = now;
            for (header, fill) in [(b'C', 0x7F), (b'c', 0x80), (b'C', 0x01), (b'C', 0xFF)] {
                let block = [&[header][..], &data(fill)].concat();
                for _ in 0..3 {
                    t += Duration::from_millis(1);
                    hand.handle_input(t, &block);
                }
            }
            hand.handle_input(t + Duration::from_millis(10), b"Aa");
            hand.handle_input(t + Duration::from_millis(500), b"A");
            hand.handle_input(t + Duration::from_millis(501), b"x");
        }
        for id in profile.param_ids() {
            send(&mut hand, &line(&format!("{} {}", profile.getter(id), profile.param(id).name)));
        }
        send(&mut hand, &[abort]);
    }
    let _ = hand.take_output();
}

// ------------------------------------------------------------------------------------- wire

/// `gcl fuzz device`'s action generator against the in-process sim, differentially: the
/// input picks (with `arbitrary`) a profile, a fault or none, and the seeds of one to six
/// groups of host actions; the case the model makes of them is replayed against the mutant.
///
/// Checks, besides not panicking: the case passes on the unmutated sim (the fuzzer's
/// oracle never blames a correct hand); its transcript text parses back (`gcl replay` reads
/// every finding it writes) and replays on the mutant with the same verdict; a failing
/// replay has a signature and a passing one none.
pub fn wire(data: &[u8]) {
    use gcl_harness::fuzz::device::action::{Allowed, Dice, Generator};
    use gcl_harness::fuzz::device::{case::build_case, signature};
    use gcl_harness::replay::replay;
    let mut u = arbitrary::Unstructured::new(data);
    let profiles = builtin_profiles();
    let Ok(pi) = u.choose_index(profiles.len()) else { return };
    let p = &profiles[pi];
    let fault: Option<Fault> = u.choose(Fault::ALL).ok().copied().filter(|_| u.arbitrary::<bool>().unwrap_or(false));
    let groups = u.int_in_range(1..=6u8).unwrap_or(1);
    let g = Generator::new(p, Allowed::default());
    let mut actions = Vec::new();
    for _ in 0..groups {
        let seed: u64 = u.arbitrary().unwrap_or(0);
        g.group(&mut Dice::new(seed), &mut actions);
    }
    let Ok(built) = build_case(p, &actions, "wire", "wire", false, false) else { return };
    let t = &built.transcript;
    let opts = gcl_harness::suite::replay_options();
    let fresh =
        |faults: Vec<Fault>| gcl_host::SimLink::new(p.clone(), DeviceConfig { faults, ..DeviceConfig::default() });
    assert!(replay(t, &mut fresh(vec![]), &opts).is_pass(), "wire: the model's own case fails on the unmutated sim");
    let Some(f) = fault else { return };
    let out = replay(t, &mut fresh(vec![f]), &opts);
    assert_eq!(
        out.is_pass(),
        signature(p, &built, &out, true).is_none(),
        "wire: a verdict and its signature disagree ({f})"
    );
    let text = t.to_text();
    let back = gcl_transcript::parse(&text).unwrap_or_else(|e| panic!("wire: the transcript does not parse back: {e}"));
    let again = replay(&back, &mut fresh(vec![f]), &opts);
    assert_eq!(again.is_pass(), out.is_pass(), "wire: the parsed transcript replays differently on {f}");
}

// ------------------------------------------------------------------------------- transcript

/// The transcript reader (`gcl replay`, `gcl fuzz device`'s findings, the suite) on untrusted
/// text.
///
/// Checks, besides not panicking: a transcript that parses prints (`to_text`) a text that
/// parses back to the same transcript, line numbers aside.
pub fn transcript(data: &[u8]) {
    let Ok(t) = gcl_transcript::parse_bytes(data) else { return };
    let text = t.to_text();
    let back = gcl_transcript::parse(&text)
        .unwrap_or_else(|e| panic!("transcript round trip: the printed text does not parse: {e}\n{text}"));
    assert_eq!(back.without_lines(), t.without_lines(), "transcript round trip: the printed text reads differently");
}

// ----------------------------------------------------------------------------------- client

/// Polls the host core may answer before it must be settled (each answer consumes bytes).
const CLIENT_POLLS: usize = 4096;

/// The host client core (`gcl_host::client::core::HostCore`) driven by the input: the first
/// byte picks the profile; then each byte is an operation (a request from [`seeds::LINES`],
/// LOOP with the profile's default layout, a RealTime block, ^C, a sync, expecting a prompt,
/// giving up) or, for bytes from 0x40, a chunk of that many bytes from the hand (the next
/// input bytes), after which the core is polled until it settles.
///
/// Checks, besides not panicking: polling settles (`Ok(None)` or a violation) within
/// `CLIENT_POLLS` polls, whatever the hand sends.
pub fn client(data: &[u8]) {
    use gcl_host::client::core::{Framing, HostCore};
    let Some((&first, mut rest)) = data.split_first() else { return };
    let profiles = builtin_profiles();
    let p = &profiles[first as usize % profiles.len()];
    let mut core = HostCore::new(Framing::of(p));
    let layout = RtLayout::compute(p, &ParamStore::defaults(p), MotorSet::from_motors([1, 2, 3, 4]));
    // A `C` block of that layout, every datum 0.
    let zeros = realtime::Control::zeroed(realtime::ControlHeader::DataFeedback, layout.control());
    while let Some((&op, tail)) = rest.split_first() {
        rest = tail;
        match op {
            0..=15 => {
                let _ = core.command(seeds::LINES[op as usize % seeds::LINES.len()]);
            }
            16 => {
                let _ = core.start_loop("LOOP", layout.clone());
            }
            17 => {
                let _ = core.block(&zeros);
            }
            18 => {
                let _ = core.block(&realtime::Control::new(realtime::ControlHeader::Ack));
            }
            19 => {
                core.abort();
            }
            20 => {
                core.sync();
            }
            21 => core.expect_prompt(),
            22 => core.give_up(),
            n if n >= 0x40 => {
                let k = ((n - 0x3f) as usize).min(rest.len());
                core.handle_input(&rest[..k]);
                rest = &rest[k..];
                let mut settled = false;
                for _ in 0..CLIENT_POLLS {
                    match core.poll() {
                        Ok(Some(_)) => {}
                        Ok(None) | Err(_) => {
                            settled = true;
                            break;
                        }
                    }
                }
                assert!(settled, "client core: poll does not settle within {CLIENT_POLLS} polls");
            }
            _ => {}
        }
    }
}
