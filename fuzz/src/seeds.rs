//! The seed corpora under `fuzz/seeds/<target>/`, generated deterministically.
//!
//! Seeds give the fuzzer a start in the interesting places (a hand after HI, a RealTime loop
//! with every flag, the embedded spec files) and give the crate's tests inputs that reach
//! them on stable. `tests/seeds.rs` checks that the committed files match [`generate`] and
//! rewrites them with `UPDATE_SEEDS=1`. Files there that this module does not generate
//! (inputs a fuzzer found, `crash-*` reproducers) are kept and run too.

use gcl_model::spec::{EMBEDDED_FILES, EMBEDDED_PROFILES, Profile, embedded};

use crate::{DeviceSession, SPEC_FILE_NAME, Step};

/// One seed file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Seed {
    /// The target, and so the directory under `seeds/`.
    pub target: &'static str,
    /// The file name.
    pub name: String,
    /// The contents.
    pub bytes: Vec<u8>,
}

/// Every generated seed, in a fixed order.
pub fn generate() -> Vec<Seed> {
    let mut seeds = Vec::new();
    seeds.extend(grammar());
    seeds.extend(device());
    seeds.extend(realtime());
    seeds.extend(spec());
    seeds.extend(wire());
    seeds.extend(transcripts());
    seeds.extend(client());
    seeds.extend(dictionaries());
    seeds
}

/// Where the libFuzzer dictionaries live: `seeds/dicts/<target>.dict` (not a target's corpus).
pub const DICTS: &str = "dicts";

/// Command lines of every shape: accepted, refused for each status bit, odd spacing and case.
pub const LINES: &[&str] = &[
    "HI",
    "FGET DP",
    "FSET DP 5000",
    "12FSET LCV 1 LCVC 1",
    "12FSET MCV 80 MOV 70",
    "GC",
    "SM 1500",
    "124LOOP",
    "PSET LFT 1",
    "PGET TEMP",
    "FGET P S SG",
    "?HI",
    "?",
    "A?",
    "ERR 5120",
    "VERS",
    "FLISTAV",
    "  gs  c ",
    "\tfset\tdp\t-0",
    "M 007",
    "BOGUS",
    "FSET DP 70000",
    "FSET DP",
    "FSET DP 1x",
    "FSET P 5",
    "C 5",
    "1RESET",
    "1VERS 3",
    "FSET NOPE 1 DP 99999",
    "?BOGUS",
    "? HI",
    "12",
    "FSET DP 1234567890123456789",
    "FGET\u{e9}",
];

fn grammar() -> Vec<Seed> {
    let mut seeds: Vec<Seed> = LINES
        .iter()
        .enumerate()
        .map(|(i, l)| Seed { target: "grammar", name: format!("line-{i:02}"), bytes: l.as_bytes().to_vec() })
        .collect();
    let all: Vec<u8> = LINES.iter().flat_map(|l| l.bytes().chain([b'\r'])).collect();
    seeds.push(Seed { target: "grammar", name: "all-lines".into(), bytes: all });
    seeds
}

/// A wait byte: run the previous command until idle (at most 8 s), then send.
const IDLE: u8 = 192 + 7;
/// A wait byte: 1 ms.
const MS1: u8 = 1;

fn step(wait: u8, bytes: &[u8]) -> Step {
    Step { wait, bytes: bytes.to_vec() }
}

fn lines(wait: u8, lines: &[&str]) -> Vec<Step> {
    lines.iter().map(|l| step(wait, format!("{l}\r").as_bytes())).collect()
}

/// Steps for a RealTime session: HI, every flag on, LOOP, blocks of each kind, ^C.
fn loop_steps() -> Vec<Step> {
    let mut steps = lines(
        IDLE,
        &["HI", "FSET LCV 1 LCVC 1 LCPG 1 LFV 1 LFS 1 LFAP 1 LFDP 1", "FSET LFBP 1 LFAIN 1", "PSET LFT 1", "LOOP"],
    );
    for (header, fill) in [(b'C', 0x10u8), (b'C', 0xF0), (b'c', 0x7F), (b'C', 0x80)] {
        let mut block = vec![header];
        block.extend(std::iter::repeat_n(fill, 8));
        steps.push(step(MS1, &block));
    }
    steps.push(step(MS1, b"A"));
    steps.push(step(MS1, b"a"));
    steps.push(step(100, b"A"));
    steps.push(step(MS1, b"\x03"));
    steps.extend(lines(IDLE, &["FGET P"]));
    steps
}

fn device() -> Vec<Seed> {
    let profiles = EMBEDDED_PROFILES.len() as u8;
    let session = |profile: u8, faults: u64, scenario: u8, steps: Vec<Step>| {
        DeviceSession { profile, faults, scenario, steps }.to_bytes()
    };
    let mut seeds = Vec::new();
    let mut add = |name: String, bytes: Vec<u8>| seeds.push(Seed { target: "device", name, bytes });
    for p in 0..profiles {
        let name = EMBEDDED_PROFILES[p as usize].0;
        add(format!("{name}-hi-close-open"), session(p, 0, 0, lines(IDLE, &["HI", "FGET P", "C", "FGET P S SG", "O"])));
        add(format!("{name}-loop-all-flags"), session(p, 0, 0, loop_steps()));
        add(
            format!("{name}-motions-objects"),
            session(
                p,
                0,
                0b0000_1011,
                lines(IDLE, &["HI", "M 5000", "IC", "IO 100", "HOME", "TC", "FGET SG", "TO", "T", "123C", "SC"]),
            ),
        );
        add(
            format!("{name}-lists-help"),
            session(
                p,
                0,
                0,
                lines(
                    0,
                    &[
                        "FLIST", "FLISTV", "FLISTA", "FLISTAV", "PLIST", "PLISTV", "PLISTA", "PLISTAV", "?", "A?",
                        "?HI", "ERR", "ERR 5", "VERS",
                    ],
                ),
            ),
        );
        add(
            format!("{name}-persist-reset"),
            session(
                p,
                0,
                0,
                lines(
                    IDLE,
                    &[
                        "FSET DP 5000",
                        "FSAVE",
                        "RESET",
                        "FGET DP",
                        "FDEF",
                        "FLOAD",
                        "PSET LFT 1",
                        "PSAVE",
                        "PDEF",
                        "PLOAD",
                        "PGET UPSECS PTEMP SN",
                    ],
                ),
            ),
        );
    }
    let mut abort = lines(IDLE, &["HI"]);
    abort.push(step(0, b"C\r"));
    abort.push(step(64 + 1, b"\x03"));
    abort.push(step(0, b"C\rFGET P\rO\r"));
    abort.push(step(IDLE, b""));
    add("abort-and-queue".into(), session(2, 0, 0, abort));
    let mut overlong = vec![step(0, &[b'A'; 100]), step(0, b"\r")];
    overlong.push(step(0, b"FGET DP\x03HI\r"));
    add("overlong-and-abort-idle".into(), session(1, 0, 0, overlong));
    let mut bad = lines(IDLE, &["HI", "LOOP"]);
    bad.push(step(MS1, b"x"));
    bad.push(step(MS1, b"FGET P\r"));
    add("bad-header".into(), session(2, 0, 0, bad));
    add("lowercase".into(), session(0, 0, 0, lines(IDLE, &["hi", "fget p", "gc", "fset dp 70000"])));
    let every_fault = u64::MAX >> (u64::BITS as usize - gcl_model::device::Fault::ALL.len());
    add("every-fault-hot-hand".into(), session(2, every_fault, 0xFF, loop_steps()));
    add("every-fault-seed".into(), session(0, every_fault, 0b0001_0100, loop_steps()));
    seeds
}

/// SplitMix64: a small deterministic generator for filler bytes.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

fn realtime() -> Vec<Seed> {
    let mut rng = SplitMix(0x6763_6c21);
    let mut seeds = Vec::new();
    for p in 0..EMBEDDED_PROFILES.len() as u8 {
        for (flags, motors) in [(0xFFFFu16, 0xFu8), (0, 0xF), (0x5555, 0x9), (0xAAAA, 0x1), (0x00FF, 0x7)] {
            for (k, lead) in [b'C', b'*', b'c'].into_iter().enumerate() {
                let mut bytes = vec![p, motors];
                bytes.extend_from_slice(&flags.to_le_bytes());
                bytes.push(lead);
                bytes.extend(rng.bytes(72));
                let name = format!("{}-flags{flags:04x}-motors{motors:x}-{k}", EMBEDDED_PROFILES[p as usize].0);
                seeds.push(Seed { target: "realtime", name, bytes });
            }
        }
    }
    seeds
}

fn spec() -> Vec<Seed> {
    let mut seeds: Vec<Seed> = EMBEDDED_PROFILES
        .iter()
        .filter_map(|(name, file)| {
            Some(Seed { target: "spec", name: (*name).into(), bytes: embedded(file)?.as_bytes().to_vec() })
        })
        .collect();
    let mut add = |name: &str, text: String| seeds.push(Seed { target: "spec", name: name.into(), bytes: text.into() });
    add("derived-4.4", "include = [\"bh8-262-4.4.toml\"]\nid = \"fuzzed\"\naliases = [\"f\"]\n".into());
    add(
        "derived-hand",
        "include = [\"bh8-262/common.toml\"]\nid = \"fuzzed-hand\"\nbanner = [\"B\"]\nversion = [\"V\"]\n\
         remove_commands = [\"A?\"]\nremove_params = [\"LFT\"]\n"
            .to_string()
            + &hand_table(),
    );
    add("include-cycle", format!("include = [\"{SPEC_FILE_NAME}\"]\nid = \"cycle\"\n"));
    add("missing-include", "include = [\"nope.toml\"]\n".into());
    add("shared-only", "include = [\"shared/framing.toml\", \"shared/status.toml\"]\nid = \"bare\"\n".into());
    add("bad-toml", "id = \"x\"\n[hand\nfinger_limit = ".into());
    add("unknown-field", "id = \"x\"\nbogus = 1\n".into());
    seeds
}

/// The `[hand]` table of bh8-262-4.4 with a few values moved, as TOML text.
fn hand_table() -> String {
    let text = embedded("bh8-262-4.4.toml").unwrap_or_default();
    let start = text.find("[hand]").unwrap_or(text.len());
    let end = text[start..].find("\n\n").map_or(text.len(), |e| start + e);
    text[start..end].replace("lcv_fraction_bits = 4", "lcv_fraction_bits = 0").replace("lft_size = 1", "lft_size = 2")
        + "\n"
}

/// One libFuzzer dictionary entry: the bytes quoted, with `\\`, `\"` and `\xNN` escapes.
fn dict_entry(bytes: &[u8]) -> String {
    let mut s = String::from("\"");
    for &b in bytes {
        match b {
            b'\\' | b'"' => {
                s.push('\\');
                s.push(b as char);
            }
            0x20..=0x7E => s.push(b as char),
            _ => s.push_str(&format!("\\x{b:02X}")),
        }
    }
    s.push('"');
    s
}

fn dict(name: &str, entries: impl IntoIterator<Item = Vec<u8>>) -> Seed {
    let mut entries: Vec<Vec<u8>> = entries.into_iter().collect();
    entries.sort();
    entries.dedup();
    let text: String = entries.iter().map(|e| dict_entry(e) + "\n").collect();
    Seed { target: DICTS, name: format!("{name}.dict"), bytes: text.into_bytes() }
}

/// Numbers at the edges of the integer types the model uses.
const EDGE_NUMBERS: &[&str] = &[
    "-1",
    "0",
    "127",
    "128",
    "255",
    "256",
    "32767",
    "65535",
    "65536",
    "2147483647",
    "4294967295",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "999999999999999999",
];

/// Dictionaries for libFuzzer (`-dict=`): the words of the protocol and of the spec files.
fn dictionaries() -> Vec<Seed> {
    let mut words: Vec<Vec<u8>> = Vec::new();
    for name in Profile::builtin_names() {
        let Ok(p) = Profile::builtin(name) else { continue };
        words.extend(p.commands.iter().map(|c| c.name.clone().into_bytes()));
        words.extend(
            p.params
                .iter()
                .flat_map(|q| std::iter::once(&q.name).chain(&q.input_aliases))
                .map(|n| n.clone().into_bytes()),
        );
        words.extend(p.prefixes.iter().map(|q| q.char.to_string().into_bytes()));
    }
    let numbers = || EDGE_NUMBERS.iter().map(|n| n.as_bytes().to_vec());
    let grammar = words.iter().cloned().chain(numbers()).chain([b" ".to_vec(), b"\t".to_vec(), b"\r".to_vec()]);
    let device = words
        .iter()
        .map(|w| [&w[..], b"\r"].concat())
        .chain(words.iter().map(|w| [&w[..], b" "].concat()))
        .chain(numbers())
        .chain([b"\r".to_vec(), vec![3], b"C".to_vec(), b"c".to_vec(), b"A".to_vec(), b"a".to_vec()]);
    let mut keys: Vec<Vec<u8>> = Vec::new();
    for (_, text) in EMBEDDED_FILES {
        for line in text.lines().map(str::trim) {
            if line.starts_with('[') {
                keys.push(line.as_bytes().to_vec());
            } else if let Some((key, _)) = line.split_once(" = ") {
                keys.push(format!("{key} = ").into_bytes());
            }
        }
    }
    let spec = keys
        .into_iter()
        .chain(numbers())
        .chain(
            ["1e308", "-1e308", "nan", "inf", "-0.0", "true", "false", "\"\"", "[]", "{}"]
                .map(|v| v.as_bytes().to_vec()),
        )
        .chain(EMBEDDED_FILES.iter().map(|(f, _)| format!("\"{f}\"").into_bytes()));
    vec![dict("grammar", grammar), dict("device", device), dict("spec", spec)]
}

/// `wire` inputs: a profile, a fault (or none), the number of groups and their seeds, as
/// `arbitrary` reads them; a spread of each.
fn wire() -> Vec<Seed> {
    (0u8..8)
        .map(|i| {
            let mut bytes = vec![i % 3, i.wrapping_mul(7), 1, 5];
            for g in 0..6u64 {
                bytes.extend((u64::from(i) * 1000 + g).to_le_bytes());
            }
            Seed { target: "wire", name: format!("seed-{i}"), bytes }
        })
        .collect()
}

/// `transcript` inputs: a few of the suite's golden transcripts of the seed profile (one of
/// each kind of step: text, hex blocks, pauses, elisions, fields), and a broken header.
fn transcripts() -> Vec<Seed> {
    let Ok(p) = Profile::builtin("seed") else { return Vec::new() };
    let cases = gcl_harness::suite::generate(&p).unwrap_or_default();
    let mut out: Vec<Seed> = [
        "framing-echo",
        "abort-motion-discards-queue",
        "rt-header-upper-c",
        "cmd-fget",
        "param-p-read-only",
        "rt-lfdp-worked-example",
    ]
    .iter()
    .filter_map(|id| cases.iter().find(|c| c.id() == *id))
    .map(|c| Seed { target: "transcript", name: c.id().to_string(), bytes: c.text().into_bytes() })
    .collect();
    out.push(Seed {
        target: "transcript",
        name: "bad-header".into(),
        bytes: b"gcl-transcript 1\nid: X\n\nsend \"A\"\n".to_vec(),
    });
    out
}

/// `client` inputs: a request and the hand's answer in chunks, for each profile and a few
/// shapes (an answer, a refusal, a LOOP with its `*` and a feedback block, garbage).
fn client() -> Vec<Seed> {
    let chunk = |bytes: &[u8]| {
        let mut v = Vec::new();
        for c in bytes.chunks(0x40) {
            v.push(0x3f + c.len() as u8);
            v.extend_from_slice(c);
        }
        v
    };
    let mut out = Vec::new();
    for p in 0..3u8 {
        let hi = [&[p, 0][..], &chunk(b"HI\n\r=> ")].concat();
        out.push(Seed { target: "client", name: format!("p{p}-answer"), bytes: hi });
        let err = [&[p, 1][..], &chunk(b"FGET DP\n\rERR 64\n\r=> ")].concat();
        out.push(Seed { target: "client", name: format!("p{p}-refusal"), bytes: err });
    }
    let lp = [&[0u8, 16][..], &chunk(b"LOOP*"), &[17][..], &chunk(&[b'*'; 22])].concat();
    out.push(Seed { target: "client", name: "loop-block".into(), bytes: lp });
    out.push(Seed { target: "client", name: "garbage".into(), bytes: [&[1u8, 3][..], &chunk(&[0xff; 100])].concat() });
    out
}
