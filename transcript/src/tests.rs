use std::time::Duration;

use proptest::prelude::*;

use super::*;

const SAMPLE: &str = r#"gcl-transcript 1
id: rt-lfap-byte-order
title: LFAP is two bytes, high byte first
clause: seed: RealTime Control
clause: decision:seed-rt-field-order
level: MUST
profile: seed, bh8-262-4.4
requires: motion, realtime
note: positions within MPE
x-origin: hand-written

# preamble
send "\x03"
expect "\n\r=> "

send "RESET\r"
expect within 10s "RESET{any}BarrettHand Firmware{any}\n\r=> "

send "1M 5000\r"
expect within 30s "1M 5000\n\r=> "

send "1FGET P\r"
expect "1FGET P\n\r{int 4950..5050}\n\r=> "

send hex 41
expect hex 2A {u16 4950..5050} ?? {i8 -3..3}

pause 200ms
send "\x03"
expect "\n\r=> "
"#;

#[test]
fn parses_every_element() {
    let t = parse(SAMPLE).unwrap();
    let h = &t.header;
    assert_eq!(h.id, "rt-lfap-byte-order");
    assert_eq!(h.clauses, vec!["seed: RealTime Control", "decision:seed-rt-field-order"]);
    assert_eq!(h.level, Level::Must);
    assert_eq!(h.profiles, vec!["seed", "bh8-262-4.4"]);
    assert_eq!(h.requires, vec![Requirement::Motion, Requirement::Realtime]);
    assert_eq!(h.extensions, vec![("x-origin".to_string(), "hand-written".to_string())]);
    assert_eq!(t.steps.len(), 6);
    assert_eq!(t.steps[0].line, 13);
    assert_eq!(t.steps[0].comments, vec!["preamble"]);
    assert_eq!(t.steps[0].send, Some(HostBytes::text(vec![3])));
    assert_eq!(t.steps[1].within, Some(Duration::from_secs(10)));
    assert_eq!(t.steps[4].send, Some(HostBytes::hex(vec![0x41])));
    let pieces: Vec<&Piece> = t.steps[4].expect.pieces().map(|(_, p)| p).collect();
    assert_eq!(
        pieces,
        vec![
            &Piece::Bytes(vec![0x2A]),
            &Piece::Field { ty: FieldType::U16, min: 4950, max: 5050 },
            &Piece::AnyByte,
            &Piece::Field { ty: FieldType::I8, min: -3, max: 3 },
        ]
    );
    assert_eq!(t.steps[5].pause, Some(Duration::from_millis(200)));
    assert!(t.steps[3].expect.matches(b"1FGET P\n\r5003\n\r=> "));
    assert!(!t.steps[3].expect.matches(b"1FGET P\n\r5051\n\r=> "));
}

#[test]
fn printing_is_canonical_and_round_trips() {
    let t = parse(SAMPLE).unwrap();
    let text = t.to_text();
    let again = parse(&text).unwrap();
    assert_eq!(again.without_lines(), t.without_lines());
    assert_eq!(again.to_text(), text);
    assert!(text.contains("expect hex 2A {u16 4950..5050} ?? {i8 -3..3}\n"));
    assert!(text.contains("profile: seed, bh8-262-4.4\n"));
}

#[test]
fn hand_written_shorthand_is_accepted() {
    // Steps without `expect` expect nothing; CRLF files read the same; `{byte}` is `??`.
    let t = parse(
        "gcl-transcript 1\r\nid: a\r\ntitle: t\r\nclause: c\r\nlevel: info\r\nprofile: seed\r\n\
         send \"A\"\r\nsend \"B\"\r\nexpect \"x\" hex 01 {byte}\r\n",
    )
    .unwrap();
    assert_eq!(t.steps.len(), 2);
    assert!(t.steps[0].expect.is_empty());
    assert_eq!(t.header.level, Level::Info);
    assert!(t.steps[1].expect.matches(b"x\x01\xFF"));
    assert_eq!(t.steps[1].expect.to_text(), "\"x\" hex 01 ??");
}

fn err(text: &str) -> ParseError {
    match parse(text) {
        Ok(t) => panic!("parsed: {t:?}"),
        Err(e) => e,
    }
}

const HEAD: &str = "gcl-transcript 1\nid: a\ntitle: t\nclause: c\nlevel: MUST\nprofile: seed\n";

#[test]
fn errors_are_typed_with_line_numbers() {
    assert_eq!(err("").kind, ParseErrorKind::MissingMagic);
    assert_eq!(err("hello\n").kind, ParseErrorKind::MissingMagic);
    let e = err("gcl-transcript 2\n");
    assert_eq!((e.line, e.kind), (1, ParseErrorKind::UnsupportedVersion("2".into())));
    let e = err("gcl-transcript 1\nid: a\nid: b\n");
    assert_eq!((e.line, e.kind), (3, ParseErrorKind::DuplicateKey("id".into())));
    let e = err("gcl-transcript 1\nid: Not A Slug\n");
    assert_eq!(e.line, 2);
    assert!(matches!(e.kind, ParseErrorKind::BadValue { .. }));
    let e = err("gcl-transcript 1\ncolour: red\n");
    assert_eq!((e.line, e.kind), (2, ParseErrorKind::UnknownKey("colour".into())));
    let e = err("gcl-transcript 1\nid: a\ntitle: t\nlevel: MUST\nprofile: seed\nsend \"x\"\n");
    assert_eq!((e.line, e.kind), (6, ParseErrorKind::MissingKey("clause".into())));
    let e = err("gcl-transcript 1\nlevel: SOMETIMES\n");
    assert_eq!(e.line, 2);
    let e = err(&format!("{HEAD}send \"x\"\nexpect \"y\"\nid: late\n"));
    assert_eq!((e.line, e.kind), (9, ParseErrorKind::HeaderInBody("id".into())));
    let e = err(&format!("{HEAD}transmit \"x\"\n"));
    assert_eq!((e.line, e.kind), (7, ParseErrorKind::UnknownDirective("transmit".into())));
    let e = err(&format!("{HEAD}pause soon\n"));
    assert_eq!((e.line, e.kind), (7, ParseErrorKind::BadDuration("soon".into())));
    let e = err(&format!("{HEAD}pause 99999999s\n"));
    assert_eq!(e.line, 7);
    let e = err(&format!("{HEAD}send \"abc\n"));
    assert_eq!((e.line, e.column), (7, Some(6)));
    assert!(matches!(e.kind, ParseErrorKind::BadString(_)));
    let e = err(&format!("{HEAD}send \"a\\qb\"\n"));
    assert_eq!((e.line, e.column), (7, Some(8)));
    // Strings and `gcl record` scripts share one unescaper: both refuse `\x+F` and raw bytes.
    let e = err(&format!("{HEAD}send \"a\\x+Fb\"\n"));
    assert_eq!((e.line, e.column), (7, Some(8)));
    assert_eq!(e.kind, ParseErrorKind::BadString("`\\x` needs two hex digits".into()));
    assert!(crate::script::parse_script("line: a\\x+F\n").is_err());
    let e = err(&format!("{HEAD}expect \"ok\u{e9}\"\n"));
    assert_eq!((e.line, e.column), (7, Some(11)));
    let e = err(&format!("{HEAD}send \"a{{int}}\"\n"));
    assert!(matches!(e.kind, ParseErrorKind::BadString(_)));
    let e = err(&format!("{HEAD}send hex 4G\n"));
    assert_eq!(e.kind, ParseErrorKind::BadHex("4G".into()));
    let e = err(&format!("{HEAD}send hex ??\n"));
    assert_eq!(e.kind, ParseErrorKind::BadHex("??".into()));
    let e = err(&format!("{HEAD}expect \"{{int 9..1}}x\"\n"));
    assert!(matches!(e.kind, ParseErrorKind::BadElision(_)));
    let e = err(&format!("{HEAD}expect hex {{u8 0..256}}\n"));
    assert!(matches!(e.kind, ParseErrorKind::BadElision(_)));
    let e = err(&format!("{HEAD}expect \"{{whatever}}x\"\n"));
    assert!(matches!(e.kind, ParseErrorKind::BadElision(_)));
    let e = err(&format!("{HEAD}expect \"x{{int}}\"\n"));
    assert!(matches!(e.kind, ParseErrorKind::BadExpect(_)));
    // {text} stands for whole lines: a line break on either side, and never at the end.
    for bad in ["x{text}\\n", "\\n{text}x", "\\n{text}", "{int}{text}\\n", "\\n{text}{int}\\n", "{text as a}\\n"] {
        let e = err(&format!("{HEAD}expect \"{bad}\"\n"));
        assert!(matches!(e.kind, ParseErrorKind::BadExpect(_) | ParseErrorKind::BadElision(_)), "{bad}: {e}");
    }
    let t = parse(&format!("{HEAD}expect \"{{text}}\\r\" hex 0A {{text}} 0D\n")).unwrap();
    assert_eq!(t.steps[0].expect.to_text(), "\"{text}\\r\" hex 0A {text} 0D");
    let e = err(&format!("{HEAD}expect \"x\" trailing\n"));
    assert_eq!(e.kind, ParseErrorKind::Unexpected("trailing".into()));
    let e = err(HEAD);
    assert_eq!(e.kind, ParseErrorKind::NoSteps);
    let e = parse_bytes(b"gcl-transcript 1\nid: \xFF\n").unwrap_err();
    assert_eq!((e.line, e.kind), (2, ParseErrorKind::NotUtf8));
    let e = err(&format!("{HEAD}send \"caf\u{e9}\"\n"));
    assert!(matches!(e.kind, ParseErrorKind::BadString(_)));
}

const RELATIONS: &str = r#"gcl-transcript 1
id: rt-lcvc-scaling
title: twice the LCVC, twice the velocity
clause: seed: Parameter LCVC
level: MUST
profile: seed

send "12FGET P\r"
expect "12FGET P\n\r{int 1..17800 as p1} {int p1*11/2 +-15%}\n\r=> "

send hex 41
expect hex 2A {i8 1..127 as v1} {i8 v1/2 +-25% as v2} {u16 p1 +-0%}

send "SM 4000\r"
expect within 5s..30s "SM 4000\n\rERR 16\n\r=> "
"#;

#[test]
fn a_setup_places_objects_and_needs_the_object_requirement() {
    let t = parse(&format!("{HEAD}requires: motion, object\nsetup: object 1 6000\nsetup:  object 3 0 \nsend \"x\"\n"))
        .unwrap();
    assert_eq!(t.header.setup, vec![Setup::Object { motor: 1, at: 6000 }, Setup::Object { motor: 3, at: 0 }]);
    assert_eq!(t.header.objects(), [Some(6000), None, Some(0), None]);
    assert!(t.to_text().contains("requires: motion, object\nsetup: object 1 6000\nsetup: object 3 0\n"));
    assert_eq!(parse(&t.to_text()).unwrap().without_lines(), t.without_lines());
    let bad = |line: &str| match err(&format!("{HEAD}requires: object\nsetup: {line}\n")).kind {
        ParseErrorKind::BadValue { key, reason } => {
            assert_eq!(key, "setup");
            reason
        }
        k => panic!("{line}: {k:?}"),
    };
    assert!(bad("object 5 100").contains("motor 1..4"));
    assert!(bad("object 01 100").contains("motor 1..4"));
    assert!(bad("object 1 -1").contains("position"));
    assert!(bad("object 1 +5").contains("position"));
    assert!(bad("object 1 1000001").contains("position"));
    assert!(bad("object 1").contains("expected"));
    assert!(bad("wall 1 100").contains("unknown setup"));
    let e = err(&format!("{HEAD}requires: object\nsetup: object 2 1\nsetup: object 2 5\n"));
    assert_eq!(e.line, 9);
    // Without `requires: object`, a runner that knows nothing of setups would run the case on
    // a hand with nothing in its way; a runner that knows the requirement skips it.
    let e = err(&format!("{HEAD}setup: object 2 1\nsend \"x\"\n"));
    assert!(e.to_string().contains("requires `object`"), "{e}");
}

#[test]
fn relations_capture_and_bound_later_values() {
    let t = parse(RELATIONS).unwrap();
    let e0 = &t.steps[0].expect;
    // The band is rounded outward: 100 * 11/2 = 550, +-15 % is 467.5..632.5, so 467..633.
    assert_eq!(Relation::new("p1", 11, 2, 15).band(100), (467, 633));
    assert_eq!(Relation::new("v", 1, 2, 25).band(-80), (-50, -30));
    let got = e0.matches_with(&Captures::new(), b"12FGET P\n\r100 633\n\r=> ").unwrap();
    assert_eq!(got.get("p1"), Some(&100));
    assert!(e0.matches(b"12FGET P\n\r100 467\n\r=> "));
    assert!(!e0.matches(b"12FGET P\n\r100 634\n\r=> "));
    assert!(!e0.matches(b"12FGET P\n\r100 466\n\r=> "));
    // The capture's own range holds: a motor that did not move cannot anchor the relation.
    assert!(!e0.matches(b"12FGET P\n\r0 0\n\r=> "));
    // Wrong values part at the first digit that cannot lead into the band.
    assert_eq!(matcher::match_prefix(e0, b"12FGET P\n\r100 9"), matcher::Outcome::Parted(14));
    // Across steps: v1 = 80, v2 within 30..50; the u16 must equal p1 (100) exactly.
    let e1 = &t.steps[1].expect;
    let next = e1.matches_with(&got, &[0x2A, 80, 40, 0, 100]).unwrap();
    assert_eq!((next.get("v1"), next.get("v2"), next.get("p1")), (Some(&80), Some(&40), Some(&100)));
    assert!(e1.matches_with(&got, &[0x2A, 80, 30, 0, 100]).is_some());
    assert!(e1.matches_with(&got, &[0x2A, 80, 51, 0, 100]).is_none());
    assert!(e1.matches_with(&got, &[0x2A, 80, 40, 0, 101]).is_none());
    // Without the earlier step's capture, the relation to p1 matches nothing.
    assert!(e1.matches_with(&Captures::new(), &[0x2A, 80, 40, 0, 100]).is_none());
    // A timing window.
    assert_eq!((t.steps[2].earliest, t.steps[2].within), (Some(Duration::from_secs(5)), Some(Duration::from_secs(30))));
}

#[test]
fn relations_and_windows_round_trip() {
    let t = parse(RELATIONS).unwrap();
    let text = t.to_text();
    assert_eq!(parse(&text).unwrap().without_lines(), t.without_lines());
    assert!(text.contains("{int 1..17800 as p1} {int p1*11/2 +-15%}"), "{text}");
    assert!(text.contains("{i8 1..127 as v1} {i8 v1/2 +-25% as v2} {u16 p1 +-0%}"), "{text}");
    assert!(text.contains("expect within 5s..30s \"SM"), "{text}");
    // `*1` and `/1` are not written.
    let one = parse(&RELATIONS.replace("v1/2 +-25%", "v1*1/1 +-25%")).unwrap();
    assert!(one.to_text().contains("{i8 v1 +-25% as v2}"));
    // A field captured without a range reads its whole type.
    let whole = parse(&RELATIONS.replace("{i8 1..127 as v1}", "{i8 as v1}")).unwrap();
    assert!(
        whole.steps[1].expect.matches_with(&[("p1".to_string(), 100)].into(), &[0x2A, 0x80, 0xC0, 0, 100]).is_some()
    );
}

#[test]
fn capture_errors_are_refused() {
    let with = |from: &str, to: &str| {
        assert!(RELATIONS.contains(from), "{from}");
        err(&RELATIONS.replace(from, to))
    };
    // A relation to a name not captured before it, here or in an earlier step.
    let e = with("{int p1*11/2 +-15%}", "{int q*11/2 +-15%}");
    assert_eq!(e.line, 8);
    assert!(matches!(e.kind, ParseErrorKind::BadCapture(_)), "{e}");
    let e = with("{int 1..17800 as p1} {int p1*11/2 +-15%}", "{int p1*11/2 +-15%} {int 1..17800 as p1}");
    assert!(matches!(e.kind, ParseErrorKind::BadCapture(_)), "{e}");
    // A name captured twice.
    let e = with("as v2", "as p1");
    assert_eq!((e.line, e.kind), (11, ParseErrorKind::BadCapture("`p1` is captured twice".into())));
    // Malformed relations and names.
    for bad in [
        "{i8 v1/2 +-25%% as v2}",
        "{i8 v1/0 +-25% as v2}",
        "{i8 v1*02 +-25% as v2}",
        "{i8 v1/2 25% as v2}",
        "{i8 v1/2 +-101% as v2}",
        "{i8 v1/2 +-25% as V2}",
        "{i8 v1/2 +-25% as}",
        "{i8 1..2 v1/2 +-25%}",
        "{i8 1..300 as v2}",
        "{line as v2}",
        "{i8 2*v1 +-25%}",
    ] {
        let e = with("{i8 v1/2 +-25% as v2}", bad);
        assert!(matches!(e.kind, ParseErrorKind::BadElision(_)), "{bad}: {e}");
    }
    let e = with("within 5s..30s", "within 30s..5s");
    assert!(matches!(e.kind, ParseErrorKind::BadCapture(_)), "{e}");
    let e = with("within 5s..30s", "within 5s..");
    assert!(matches!(e.kind, ParseErrorKind::BadDuration(_)), "{e}");
    // A capture of a varying length must not end an expectation, like {int}.
    let e = err(&format!("{HEAD}expect \"x{{int as a}}\"\n"));
    assert!(matches!(e.kind, ParseErrorKind::BadExpect(_)), "{e}");
}

#[test]
fn errors_display_with_their_line() {
    let e = err(&format!("{HEAD}pause soon\n"));
    assert_eq!(e.to_string(), "line 7: bad duration `soon` (expected e.g. 200ms or 20s, at most 24 h)");
}

// ---------------------------------------------------------------- property: parse(print(t)) == t

fn arb_text() -> impl Strategy<Value = String> {
    "[A-Za-z0-9 ,.:;()'+*/=_-]{1,30}".prop_map(|s| s.trim().to_string()).prop_filter("non-empty", |s| !s.is_empty())
}

fn arb_slug() -> impl Strategy<Value = String> {
    "[a-z0-9][a-z0-9._-]{0,20}"
}

fn arb_duration() -> impl Strategy<Value = Duration> {
    prop_oneof![(0u64..100_000).prop_map(Duration::from_millis), (1u64..3600).prop_map(Duration::from_secs)]
}

fn arb_field() -> impl Strategy<Value = Piece> {
    let types = [FieldType::U8, FieldType::I8, FieldType::U16, FieldType::I16];
    (proptest::sample::select(types.to_vec()), any::<i64>(), any::<i64>()).prop_map(|(ty, a, b)| {
        let (lo, hi) = ty.range().into_inner();
        let span = (hi - lo + 1) as u64;
        let x = lo + (a as u64 % span) as i64;
        let y = lo + (b as u64 % span) as i64;
        Piece::Field { ty, min: x.min(y), max: x.max(y) }
    })
}

fn arb_piece() -> impl Strategy<Value = Piece> {
    prop_oneof![
        4 => proptest::collection::vec(any::<u8>(), 1..8).prop_map(Piece::Bytes),
        1 => Just(Piece::Int(None)),
        1 => (-1_000_000i64..1_000_000, 0i64..1_000_000).prop_map(|(a, d)| Piece::Int(Some((a, a + d)))),
        1 => Just(Piece::Line),
        1 => Just(Piece::Any),
        1 => Just(Piece::Text),
        1 => Just(Piece::AnyByte),
        1 => arb_field(),
    ]
}

fn arb_expect() -> impl Strategy<Value = Expect> {
    proptest::collection::vec((any::<bool>(), arb_piece()), 0..8).prop_map(|ps| {
        let mut e = Expect::default();
        for (hex, p) in ps {
            let form = if hex { Form::Hex } else { Form::Text };
            // The format puts {text} between line breaks.
            let text = p == Piece::Text;
            if text {
                e.push_bytes(form, b"\n");
            }
            e.push(form, p);
            if text {
                e.push_bytes(form, b"\r");
            }
        }
        // The format forbids a variable elision at the end.
        if e.pieces().last().is_some_and(|(_, p)| p.is_variable()) {
            e.push_bytes(Form::Text, b"=> ");
        }
        e
    })
}

fn arb_step() -> impl Strategy<Value = Step> {
    (
        proptest::collection::vec(arb_text(), 0..2),
        proptest::option::of(arb_duration()),
        proptest::option::of((proptest::collection::vec(any::<u8>(), 0..10), any::<bool>())),
        proptest::option::of((arb_duration(), proptest::option::of(arb_duration()))),
        arb_expect(),
    )
        .prop_map(|(comments, pause, send, window, expect)| {
            // A window's lower bound is never above its upper.
            let (within, earliest) = match window {
                Some((w, Some(a))) => (Some(w.max(a)), Some(w.min(a))),
                Some((w, None)) => (Some(w), None),
                None => (None, None),
            };
            Step {
                line: 0,
                comments,
                pause,
                send: send.map(|(bytes, hex)| HostBytes { bytes, form: if hex { Form::Hex } else { Form::Text } }),
                within,
                earliest,
                expect,
            }
        })
}

fn arb_requirement() -> impl Strategy<Value = Requirement> {
    prop_oneof![
        Just(Requirement::Motion),
        Just(Requirement::Realtime),
        Just(Requirement::Eeprom),
        Just(Requirement::AbortTiming),
        "[a-z][a-z0-9-]{0,10}".prop_map(|s| Requirement::from_slug(&s).unwrap_or(Requirement::Motion)),
    ]
}

fn arb_transcript() -> impl Strategy<Value = Transcript> {
    (
        arb_slug(),
        arb_text(),
        proptest::collection::vec(arb_text(), 1..3),
        prop_oneof![Just(Level::Must), Just(Level::Should), Just(Level::May), Just(Level::Info)],
        proptest::collection::vec("[a-z0-9][a-z0-9.-]{0,12}", 1..3),
        proptest::collection::btree_set(arb_requirement(), 0..3),
        proptest::collection::vec(arb_text(), 0..2),
        proptest::collection::vec(arb_step(), 1..6),
        proptest::collection::btree_map(1u8..=4, 0..=MAX_OBJECT_POSITION, 0..3),
    )
        .prop_map(|(id, title, clauses, level, profiles, requires, notes, steps, objects)| Transcript {
            header: Header {
                id,
                title,
                clauses,
                level,
                profiles,
                requires: {
                    let mut r: Vec<Requirement> = requires.into_iter().collect();
                    if !objects.is_empty() && !r.contains(&Requirement::Object) {
                        r.push(Requirement::Object);
                    }
                    r
                },
                setup: objects.into_iter().map(|(motor, at)| Setup::Object { motor, at }).collect(),
                notes,
                extensions: vec![("x-seed".into(), "42".into())],
            },
            steps,
        })
}

proptest! {
    #[test]
    fn parse_print_round_trip(t in arb_transcript()) {
        let text = t.to_text();
        let back = parse(&text).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        prop_assert_eq!(back.without_lines(), t);
        prop_assert_eq!(back.to_text(), text);
    }

    #[test]
    fn parse_never_panics(s in "(gcl-transcript 1\n)?[ -~\n\t\u{80}-\u{10ff}]{0,300}") {
        let _ = parse(&s);
    }

    #[test]
    fn exact_expectations_match_their_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..40)) {
        prop_assert!(Expect::text(&bytes).matches(&bytes));
        prop_assert!(Expect::hex(&bytes).matches(&bytes));
        if !bytes.is_empty() {
            prop_assert!(!Expect::text(&bytes).matches(&bytes[..bytes.len() - 1]));
        }
    }
}
