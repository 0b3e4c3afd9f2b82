//! Properties of the whole simulated hand: it survives any bytes at any times, answers every
//! supervisory line with exactly one prompt, does not care how its input is chunked, encodes
//! RealTime blocks reversibly, and keeps its parameters in range through FSET, FSAVE, FLOAD,
//! FDEF and RESET.

use std::collections::BTreeMap;
use std::time::Duration;

use gcl_model::params::ParamStore;
use gcl_model::realtime::BlockError;
use gcl_model::spec::{BlockKind, ParamId, Scope};
use gcl_model::{Device, Mode, MotorSet, Profile, RtLayout};
use proptest::prelude::*;
use proptest::sample::select;

const PROFILES: [&str; 3] = ["seed", "bh8-262-4.3", "bh8-262-4.4"];
const PROMPT: &[u8] = b"\n\r=> ";

use crate::support;
use support::{hand, profile, send, send_bytes};

fn count(haystack: &[u8], needle: &[u8]) -> usize {
    haystack.windows(needle.len()).filter(|w| *w == needle).count()
}

// ------------------------------------------------------------------ any bytes, any times

/// Pieces of real conversations, so that random streams reach RealTime mode, motion and
/// RESET, not only error paths.
const FRAGMENTS: &[&[u8]] = &[
    b"HI\r",
    b"\r",
    b"\x03",
    b"C\r",
    b"O\r",
    b"123C\r",
    b"M 5000\r",
    b"124LOOP\r",
    b"LOOP\r",
    b"A",
    b"a",
    b"C\x10\x20",
    b"c\x7f\x80",
    b"FGET P\r",
    b"FSET LCV 1 LCPG 1 LFDP 1 LFAP 1\r",
    b"PSET LFT 1\r",
    b"FSAVE\r",
    b"RESET\r",
    b"?\r",
    b"A?\r",
    b"FLISTAV\r",
    b"ERR\r",
    b"PGET TEMP\r",
];

/// A stream: chunks of bytes, each after a gap in milliseconds.
fn stream() -> impl Strategy<Value = Vec<(u64, Vec<u8>)>> {
    let bytes = prop_oneof![
        3 => proptest::collection::vec(any::<u8>(), 0..16),
        2 => select(FRAGMENTS).prop_map(<[u8]>::to_vec),
    ];
    proptest::collection::vec((prop_oneof![3 => Just(0u64), 2 => 0u64..400], bytes), 0..40)
}

/// Runs a stream through a hand; returns everything it wrote.
fn run_stream(d: &mut Device, stream: &[(u64, Vec<u8>)]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut now = d.now();
    for (gap, bytes) in stream {
        now += Duration::from_millis(*gap);
        d.handle_input(now, bytes);
        out.extend(d.take_output());
    }
    out
}

/// Most any line can make a hand say (the longest help list is well under this).
const MAX_ANSWER: usize = 8192;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn any_bytes_at_any_times_never_panic_and_output_stays_bounded(
        name in select(PROFILES.to_vec()),
        stream in stream(),
    ) {
        let mut d = hand(name);
        let mut out = run_stream(&mut d, &stream);
        // With no more input the hand finishes what it is doing (and the input queued
        // meanwhile), then falls silent.
        let later = d.now() + Duration::from_secs(300);
        d.handle_timeout(later);
        out.extend(d.take_output());
        prop_assert_ne!(d.mode(), Mode::Busy);
        d.handle_timeout(later + Duration::from_secs(300));
        prop_assert_eq!(d.take_output(), Vec::<u8>::new());
        let input: Vec<u8> = stream.iter().flat_map(|(_, b)| b.iter().copied()).collect();
        // Every byte is echoed at most once or starts at most one RealTime block; every CR
        // or ^C ends at most one answer.
        let ends = input.iter().filter(|b| **b == b'\r' || **b == 3).count();
        prop_assert!(out.len() <= 64 * input.len() + MAX_ANSWER * ends, "{} bytes out for {} in", out.len(), input.len());
    }

    #[test]
    fn chunking_does_not_change_the_bytes(
        name in select(PROFILES.to_vec()),
        stream in stream(),
        cuts in proptest::collection::vec(any::<proptest::sample::Index>(), 0..40),
    ) {
        let mut whole = hand(name);
        let a = run_stream(&mut whole, &stream);
        // The same bytes at the same times, cut into other pieces.
        let mut pieces = Vec::new();
        for (i, (gap, bytes)) in stream.iter().enumerate() {
            match cuts.get(i) {
                Some(cut) if !bytes.is_empty() => {
                    let k = cut.index(bytes.len() + 1);
                    pieces.push((*gap, bytes[..k].to_vec()));
                    pieces.push((0, bytes[k..].to_vec()));
                }
                _ => pieces.push((*gap, bytes.clone())),
            }
        }
        let mut cut = hand(name);
        let b = run_stream(&mut cut, &pieces);
        // And one byte at a time.
        let singles: Vec<(u64, Vec<u8>)> = stream
            .iter()
            .flat_map(|(gap, bytes)| {
                let mut v = vec![(*gap, Vec::new())];
                v.extend(bytes.iter().map(|b| (0, vec![*b])));
                v
            })
            .collect();
        let mut single = hand(name);
        let c = run_stream(&mut single, &singles);
        prop_assert_eq!(&a, &b, "{:?}", String::from_utf8_lossy(&a));
        prop_assert_eq!(&a, &c);
        prop_assert_eq!(whole.params(), cut.params());
        prop_assert_eq!(whole.nv(), single.nv());
        prop_assert_eq!(whole.mode(), single.mode());
    }
}

// ------------------------------------------------------------------ one prompt per line

/// Words that cannot enter RealTime mode (no `L`) or reset the hand.
fn supervisory_token() -> impl Strategy<Value = String> {
    let words = vec![
        "FGET", "FSET", "HI", "ERR", "VERS", "?", "?HI", "A?", "C", "O", "M", "T", "IC", "IO", "HOME", "TC", "TO",
        "FSAVE", "FDEF", "PGET", "PSET", "DP", "DS", "MCX", "P", "S", "SG", "TEMP", "TMP", "BAUD", "ACCEL", "HOSG",
        "OT", "CT", "EN", "MPE", "1", "2", "3", "4", "G", "S", "12", "gs", "fget", "Hi",
    ];
    prop_oneof![
        4 => select(words).prop_map(str::to_string),
        2 => (0u32..25_000).prop_map(|v| v.to_string()),
        1 => "[ -~]{1,6}",
    ]
}

fn supervisory_line() -> impl Strategy<Value = String> {
    (proptest::collection::vec((supervisory_token(), "[ \t]{0,2}"), 0..8), "[ \t]{0,2}", 0usize..3)
        .prop_map(|(tokens, lead, long)| {
            let mut s = lead;
            for (t, sep) in tokens {
                s.push_str(&t);
                s.push_str(if sep.is_empty() { " " } else { &sep });
            }
            // Now and then a line past the 80-byte limit.
            if long == 0 {
                s.push_str(&"X".repeat(90));
            }
            s
        })
        .prop_filter("stays in supervisory mode", |s| {
            !s.contains(['L', 'l']) && !s.to_ascii_uppercase().contains("RESET")
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn every_line_gets_its_echo_and_exactly_one_prompt(
        name in select(PROFILES.to_vec()),
        lines in proptest::collection::vec(supervisory_line(), 1..12),
    ) {
        let mut d = hand(name);
        let mut all = Vec::new();
        for line in &lines {
            let out = send_bytes(&mut d, line);
            prop_assert_eq!(d.mode(), Mode::Idle, "{:?} still running", line);
            prop_assert!(out.starts_with(line.as_bytes()), "{:?} answered {:?}", line, String::from_utf8_lossy(&out));
            prop_assert!(out.ends_with(PROMPT), "{:?} answered {:?}", line, String::from_utf8_lossy(&out));
            prop_assert_eq!(count(&out, PROMPT), 1, "{:?} answered {:?}", line, String::from_utf8_lossy(&out));
            all.extend(out);
        }
        prop_assert_eq!(count(&all, PROMPT), lines.len());
    }
}

// ------------------------------------------------------------------ RealTime blocks

/// Random RealTime flags in a store, and the motors of a loop.
fn flags_and_motors() -> impl Strategy<Value = (&'static str, Vec<bool>, MotorSet)> {
    (select(PROFILES.to_vec()), proptest::collection::vec(any::<bool>(), 64), (0u8..16).prop_map(MotorSet::from_bits))
}

fn layout_of(name: &str, flags: &[bool], motors: MotorSet) -> RtLayout {
    let p = profile(name);
    let mut store = ParamStore::defaults(&p);
    let rt: Vec<ParamId> = p.param_ids().filter(|id| p.param(*id).rt.is_some()).collect();
    let mut bits = flags.iter().cycle();
    for id in rt {
        let sets: Vec<MotorSet> = match p.param(id).scope {
            Scope::Motor => (1..=4).filter_map(MotorSet::single).collect(),
            Scope::Global => vec![MotorSet::ALL],
        };
        for s in sets {
            let v = i64::from(*bits.next().unwrap());
            store.set(&p, id, s, v).unwrap();
        }
    }
    RtLayout::compute(&p, &store, motors)
}

/// A layout and one in-range value per field of each block.
fn layout_and_values() -> impl Strategy<Value = (RtLayout, Vec<i64>, Vec<i64>)> {
    flags_and_motors().prop_flat_map(|(name, flags, motors)| {
        let l = layout_of(name, &flags, motors);
        let control: Vec<_> = l.control().fields().iter().map(|f| f.min()..=f.max()).collect();
        let feedback: Vec<_> = l.feedback().fields().iter().map(|f| f.min()..=f.max()).collect();
        (Just(l), control, feedback)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn realtime_blocks_decode_to_what_was_encoded(
        (layout, control, feedback) in layout_and_values(),
        ack in any::<bool>(),
    ) {
        for (block, values, header) in [
            (&layout.control(), &control, if ack { b'c' } else { b'C' }),
            (&layout.feedback(), &feedback, b'*'),
        ] {
            // The fields tile the block after its header, motors in ascending order.
            let mut offset = 1;
            for f in block.fields() {
                prop_assert_eq!(f.offset(), offset);
                prop_assert!(f.motor().is_none_or(|m| layout.motors().contains(m)));
                offset += f.size();
            }
            prop_assert_eq!(block.size(), offset);
            let motors: Vec<u8> = block.fields().iter().filter_map(|f| f.motor()).collect();
            prop_assert!(motors.is_sorted());
            prop_assert!(block.fields().iter().skip_while(|f| f.motor().is_some()).all(|f| f.motor().is_none()));

            let mut bytes = Vec::new();
            block.encode(header, values, &mut bytes).unwrap();
            prop_assert_eq!(bytes.len(), block.size());
            prop_assert_eq!(block.decode(&bytes), Ok((header, values.clone())));
            // Two-byte fields go high byte first.
            for (f, v) in block.fields().iter().zip(values.iter()) {
                if f.size() == 2 {
                    let raw = u16::from_be_bytes([bytes[f.offset()], bytes[f.offset() + 1]]);
                    let back = if f.signed() { i64::from(raw as i16) } else { i64::from(raw) };
                    prop_assert_eq!(back, *v);
                }
            }
        }
    }

    #[test]
    fn malformed_blocks_are_errors_not_panics(
        (layout, control, feedback) in layout_and_values(),
        junk in proptest::collection::vec(any::<u8>(), 0..40),
        header in any::<u8>(),
    ) {
        for (block, values, kind) in [(&layout.control(), &control, BlockKind::Control), (&layout.feedback(), &feedback, BlockKind::Feedback)] {
            let good_header = if kind == BlockKind::Control { b'C' } else { b'*' };
            let mut bytes = Vec::new();
            block.encode(good_header, values, &mut bytes).unwrap();
            // Too short and too long.
            for n in 0..bytes.len() {
                prop_assert_eq!(block.decode(&bytes[..n]), Err(BlockError::Length { got: n, want: block.size() }));
            }
            let mut longer = bytes.clone();
            longer.push(0);
            prop_assert_eq!(block.decode(&longer), Err(BlockError::Length { got: block.size() + 1, want: block.size() }));
            // Random bytes of any length: a value or a typed error.
            let _ = block.decode(&junk);
            // A header that does not belong to this kind of block.
            let mut wrong = bytes.clone();
            wrong[0] = header;
            let fits = match kind {
                BlockKind::Control => header == b'C' || header == b'c',
                BlockKind::Feedback => header == b'*',
            };
            match block.decode(&wrong) {
                Ok((h, vs)) => {
                    prop_assert!(fits);
                    prop_assert_eq!(h, header);
                    prop_assert_eq!(&vs, values);
                }
                Err(e) => {
                    prop_assert!(!fits);
                    prop_assert_eq!(e, BlockError::Header(header));
                }
            }
            // Values that do not fit are refused when encoding.
            if let Some(f) = block.fields().first() {
                let mut too_big = values.clone();
                too_big[0] = f.max() + 1;
                let refused = matches!(block.encode(good_header, &too_big, &mut Vec::new()), Err(BlockError::Range { .. }));
                prop_assert!(refused);
            }
            let mut extra = values.clone();
            extra.push(0);
            prop_assert_eq!(
                block.encode(good_header, &extra, &mut Vec::new()),
                Err(BlockError::Arity { got: values.len() + 1, want: values.len() })
            );
        }
    }
}

// ------------------------------------------------------------------ parameter store

/// The parameters FSET writes and FGET reads, with their ids.
fn fset_params(p: &Profile) -> Vec<(ParamId, String)> {
    p.param_ids()
        .filter(|id| {
            let q = p.param(*id);
            p.setter(*id) == "FSET" && p.getter(*id) == "FGET" && !q.read_only && !q.live
        })
        .map(|id| (id, p.param(id).name.clone()))
        .collect()
}

fn persisted(p: &Profile, id: ParamId, cmd: &str) -> bool {
    p.param(id).persist.iter().any(|c| c == cmd)
}

/// Values of every FSET parameter as FGET prints them, per motor 1..=4.
fn read_all(d: &mut Device) -> BTreeMap<String, Vec<i64>> {
    let p = d.profile().clone();
    let names: Vec<String> = fset_params(&p).into_iter().map(|(_, n)| n).collect();
    let mut out = BTreeMap::new();
    // Lines stay within the 80-byte limit.
    let mut chunks: Vec<Vec<String>> = vec![Vec::new()];
    for n in names {
        let len: usize = chunks.last().unwrap().iter().map(|x| x.len() + 1).sum();
        if len + n.len() + 6 > 80 {
            chunks.push(Vec::new());
        }
        chunks.last_mut().unwrap().push(n);
    }
    for chunk in chunks {
        let line = format!("FGET {}", chunk.join(" "));
        let answer = send(d, &line);
        let body = answer.strip_prefix(&line).unwrap().strip_suffix("\n\r=> ").unwrap();
        let rows: Vec<&str> = body.split("\n\r").skip(1).collect();
        assert_eq!(rows.len(), chunk.len(), "{answer:?}");
        for (n, row) in chunk.iter().zip(rows) {
            let vals: Vec<i64> = row.split(' ').map(|v| v.parse().unwrap()).collect();
            assert_eq!(vals.len(), 4, "{row:?}");
            out.insert(n.clone(), vals);
        }
    }
    out
}

/// Every value read is one the spec allows.
fn in_range(p: &Profile, values: &BTreeMap<String, Vec<i64>>) -> Result<(), TestCaseError> {
    for (name, vs) in values {
        let id = p.param_id(name).unwrap();
        for v in vs {
            prop_assert!(p.value_ok(id, *v), "{} = {} is outside its range", name, v);
        }
    }
    Ok(())
}

/// An FSET line, valid or not: a prefix, then pairs whose values may be out of range or not
/// numbers, and now and then a read-only or unknown name.
fn fset_line(name: &'static str) -> impl Strategy<Value = String> {
    let p = profile(name);
    let names: Vec<String> = fset_params(&p).into_iter().map(|(_, n)| n).collect();
    let pair = (
        prop_oneof![8 => select(names), 1 => Just("P".to_string()), 1 => Just("NOPE".to_string())],
        prop_oneof![
            6 => (0i64..300).prop_map(|v| v.to_string()),
            2 => (0i64..70_000).prop_map(|v| v.to_string()),
            1 => (-5i64..0).prop_map(|v| v.to_string()),
            1 => Just("1x".to_string()),
        ],
    );
    (proptest::option::of((1u8..16).prop_map(MotorSet::from_bits)), proptest::collection::vec(pair, 1..4)).prop_map(
        |(prefix, pairs)| {
            let mut s = prefix.map(|m| m.to_string()).unwrap_or_default();
            s.push_str("FSET");
            for (n, v) in pairs {
                s.push_str(&format!(" {n} {v}"));
            }
            s
        },
    )
}

fn phases() -> impl Strategy<Value = (&'static str, [Vec<String>; 4])> {
    select(PROFILES.to_vec()).prop_flat_map(|name| {
        let phase = || proptest::collection::vec(fset_line(name), 0..8);
        (Just(name), [phase(), phase(), phase(), phase()])
    })
}

fn fset_all(d: &mut Device, lines: &[String]) -> Result<(), TestCaseError> {
    for l in lines {
        let answer = send(d, l);
        prop_assert!(answer == format!("{l}\n\r=> ") || answer.starts_with(&format!("{l}\n\rERR ")), "{:?}", answer);
    }
    let p = d.profile().clone();
    in_range(&p, &read_all(d))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn saved_loaded_and_default_values_come_back((name, [one, two, three, four]) in phases()) {
        let p = profile(name);
        let params = fset_params(&p);
        let defaults: BTreeMap<String, Vec<i64>> =
            params.iter().map(|(id, n)| (n.clone(), (1..=4).map(|m| p.default_for(*id, m)).collect())).collect();
        let mut d = hand(name);
        prop_assert_eq!(&read_all(&mut d), &defaults);

        fset_all(&mut d, &one)?;
        let saved = read_all(&mut d);
        prop_assert_eq!(send(&mut d, "FSAVE"), "FSAVE\n\r=> ");

        fset_all(&mut d, &two)?;
        let before = read_all(&mut d);
        prop_assert_eq!(send(&mut d, "FLOAD"), "FLOAD\n\r=> ");
        let loaded = read_all(&mut d);
        for (id, n) in &params {
            let want = if persisted(&p, *id, "FLOAD") { &saved[n] } else { &before[n] };
            prop_assert_eq!(&loaded[n], want, "FLOAD of {}", n);
        }

        fset_all(&mut d, &three)?;
        let before = read_all(&mut d);
        prop_assert_eq!(send(&mut d, "FDEF"), "FDEF\n\r=> ");
        let defaulted = read_all(&mut d);
        for (id, n) in &params {
            let want = if persisted(&p, *id, "FDEF") { &defaults[n] } else { &before[n] };
            prop_assert_eq!(&defaulted[n], want, "FDEF of {}", n);
        }

        fset_all(&mut d, &four)?;
        let answer = send(&mut d, "RESET");
        prop_assert!(answer.starts_with("RESET\n\rBarrettHand Firmware"), "{:?}", answer);
        let reset = read_all(&mut d);
        for (id, n) in &params {
            // RESET is a power cycle: factory defaults, then FLOAD of what was saved.
            let want = if persisted(&p, *id, "FLOAD") { &saved[n] } else { &defaults[n] };
            prop_assert_eq!(&reset[n], want, "RESET of {}", n);
        }
    }
}

// ------------------------------------------------------------------ regressions

/// A HI that cannot open a motor (the seed allows an open velocity of 0) used to run
/// forever; now the motor stalls after TSTOP ms like any other and stays uninitialised.
#[test]
fn hi_that_cannot_open_a_motor_ends() {
    let mut d = hand("seed");
    assert_eq!(send(&mut d, "HI"), "HI\n\r=> ");
    assert_eq!(send(&mut d, "123C"), "123C\n\r=> ");
    assert_eq!(send(&mut d, "FSET MOV 0"), "FSET MOV 0\n\r=> ");
    let t0 = d.now();
    assert_eq!(send(&mut d, "HI"), "HI\n\r=> ");
    assert_eq!(d.mode(), Mode::Idle);
    assert!(d.now() - t0 < Duration::from_secs(1), "{:?}", d.now() - t0);
    // The fingers could not open; the spread was already at its stop.
    assert_eq!(send(&mut d, "FGET S P"), "FGET S P\n\r1 1 1 0\n\r17000 17000 17000 0\n\r=> ");
    assert_eq!(send(&mut d, "1C"), "1C\n\rERR 4\n\r=> ");
    assert_eq!(send(&mut d, "FSET MOV 55"), "FSET MOV 55\n\r=> ");
    assert_eq!(send(&mut d, "HI"), "HI\n\r=> ");
    assert_eq!(send(&mut d, "FGET S P"), "FGET S P\n\r0 0 0 0\n\r0 0 0 0\n\r=> ");
}

/// PGET prints one value per name, not one per motor.
#[test]
fn pget_prints_one_value() {
    let mut d = hand("seed");
    let answer = send(&mut d, "PGET TEMP TMP");
    let rows: Vec<&str> = answer.split("\n\r").collect();
    assert_eq!(rows.len(), 4, "{answer:?}");
    assert!(rows[1..3].iter().all(|r| r.parse::<i64>().is_ok()), "{answer:?}");
    let mut b = hand("bh8-262");
    assert_eq!(send(&mut b, "PGET BAUD LFT"), "PGET BAUD LFT\n\r96\n\r0\n\r=> ");
}
