//! Throughput and size figures of the reference model.
//!
//! Run with `cargo bench -p gcl-model --bench model -- --warm-up-time 1 --measurement-time 3`.
//! Criterion prints its own estimates (with `Throughput::Elements`, as elements/s); after the
//! runs this binary prints one `summary:` line per figure, computed from the same timed
//! iterations (every element criterion timed, divided by the time it took), followed by the
//! heap allocations each element cost and the aim the figure is held against.
//!
//! Figures:
//! - `parse`: `parse_line` on a fixed mix of valid and invalid lines, profile bh8-262;
//! - `device-supervisory`: FSET/FGET lines fed to a `Device` through `handle_input`, output
//!   drained with `drain_output` into a reused buffer after each line, as a transport does;
//! - `realtime`: `C` blocks with control data on 4 motors with every control and feedback
//!   flag of bh8-262-4.4 on (LCT off: it replaces LCV), both at one instant (protocol work
//!   only) and 1 ms apart (a 1 kHz loop, one physics tick per block);
//! - `device-state`: `size_of::<Device>()` plus the heap the device owns, measured with a
//!   counting global allocator (bytes allocated and not freed while building it).
//!
//! The counting allocator (`stats_alloc`) adds a few atomic additions to every allocation in
//! this binary, so alloc-heavy paths read slightly slower here than in the harness.
//!
//! Under `cargo test --all-targets` (no `--bench` argument) criterion runs each routine once
//! and this binary checks that every workload does what it claims (the lines are accepted or
//! refused as intended, each block gets its feedback) instead of printing figures.

use std::alloc::System;
use std::cell::Cell;
use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput};
use gcl_model::device::Device;
use gcl_model::grammar::parse_line;
use gcl_model::spec::{Profile, embedded};
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// The parse mix: `(line, accepted)`. Half valid, half refused for one reason or another.
const PARSE_MIX: &[(&str, bool)] = &[
    ("HI", true),
    ("FGET DP", true),
    ("FSET DP 5000", true),
    ("12FSET MCV 80 MOV 70", true),
    ("GC", true),
    ("SM 1500", true),
    ("PSET LFT 1", true),
    ("FGET P S SG", true),
    ("?HI", true),
    ("124LOOP", true),
    ("fset lcv 1 lcvc 1 lfv 1 lfs 1", true),
    ("", true),
    ("BOGUS", false),
    ("FSET DP 70000", false),
    ("FGET NOPE", false),
    ("C 5", false),
    ("1RESET", false),
    ("FSET DP", false),
    ("FSET P 5", false),
    ("M 1 2", false),
    ("FSET NOPE 1 DP 99999", false),
    ("?BOGUS", false),
    ("12", false),
    ("FSET DP 1x", false),
];

/// The supervisory session: each line is one command.
const SUPERVISORY_LINES: &[&[u8]] = &[b"FSET DP 5000\r", b"FGET DP MCV\r", b"12FSET MCV 80 MOV 70\r", b"FGET P\r"];

/// Elements and time criterion measured for one figure.
#[derive(Default)]
struct Tally {
    elements: Cell<u64>,
    time: Cell<Duration>,
    allocations: Cell<u64>,
}

impl Tally {
    fn add(&self, elements: u64, time: Duration, allocations: usize) {
        self.elements.set(self.elements.get() + elements);
        self.time.set(self.time.get() + time);
        self.allocations.set(self.allocations.get() + allocations as u64);
    }

    fn per_second(&self) -> f64 {
        self.elements.get() as f64 / self.time.get().as_secs_f64().max(f64::MIN_POSITIVE)
    }

    fn allocations_per_element(&self) -> f64 {
        self.allocations.get() as f64 / self.elements.get().max(1) as f64
    }
}

/// Times `iters` runs of `routine` (each handling `per_iter` elements), tallying the result.
fn timed(tally: &Tally, iters: u64, per_iter: u64, mut routine: impl FnMut()) -> Duration {
    let region = Region::new(GLOBAL);
    let start = Instant::now();
    for _ in 0..iters {
        routine();
    }
    let elapsed = start.elapsed();
    tally.add(iters * per_iter, elapsed, region.change().allocations);
    elapsed
}

fn profile() -> Arc<Profile> {
    Profile::builtin("bh8-262").expect("bh8-262 is embedded")
}

/// A bh8-262 hand after HI, output drained.
fn initialized_hand() -> Device {
    let mut d = Device::with_profile(profile());
    send(&mut d, b"HI\r");
    assert!(gcl_model::Motor::ALL.into_iter().all(|m| d.initialized(m)), "HI initialises every motor");
    d
}

/// Sends bytes, runs the command to completion, returns the output.
fn send(d: &mut Device, bytes: &[u8]) -> Vec<u8> {
    let now = d.now();
    d.handle_input(now, bytes);
    d.run_until_idle(Duration::from_secs(120));
    d.take_output()
}

/// A hand in RealTime mode on motors 1..=4 with every feedback flag and LCV/LCPG on.
fn looping_hand() -> Device {
    let mut d = initialized_hand();
    let setup: &[&[u8]] =
        &[b"FSET LCV 1 LCVC 1 LCPG 1 LCT 0 LFV 1 LFS 1 LFAP 1 LFDP 1 LFBP 1 LFAIN 1\r", b"PSET LFT 1\r"];
    for line in setup {
        let out = send(&mut d, line);
        assert!(!out.windows(3).any(|w| w == b"ERR"), "{}", String::from_utf8_lossy(&out));
    }
    let out = send(&mut d, b"LOOP\r");
    assert!(out.ends_with(b"*"), "LOOP answers `*`: {}", String::from_utf8_lossy(&out));
    d
}

/// `C` control blocks for the loop's layout: LCV alternating ±8 (±0.5 in 4.4 fixed point),
/// LCPG 10, so the fingers move back and forth and stay inside their stops.
fn control_blocks(d: &Device) -> (Vec<Vec<u8>>, usize) {
    let layout = d.rt_layout().expect("in LOOP");
    assert_eq!(layout.motors().len(), 4);
    let blocks = [8, -8]
        .iter()
        .map(|lcv| {
            let values: Vec<i64> =
                layout.control().fields().iter().map(|f| if f.name() == "LCV" { *lcv } else { 10 }).collect();
            let mut block = Vec::new();
            layout.control().encode(b'C', &values, &mut block).expect("values fit");
            block
        })
        .collect();
    (blocks, layout.feedback().size())
}

fn bench_parse(c: &mut Criterion, tally: &Tally) {
    let p = profile();
    let lines: Vec<&[u8]> = PARSE_MIX.iter().map(|(l, _)| l.as_bytes()).collect();
    for (line, accepted) in PARSE_MIX {
        assert_eq!(parse_line(&p, line.as_bytes()).is_ok(), *accepted, "{line:?}");
    }
    let n = lines.len() as u64;
    let mut g = c.benchmark_group("parse");
    g.throughput(Throughput::Elements(n));
    g.bench_function("parse_line/bh8-262 mix", |b| {
        b.iter_custom(|iters| {
            timed(tally, iters, n, || {
                for l in &lines {
                    let _ = black_box(parse_line(&p, black_box(l)));
                }
            })
        })
    });
    g.finish();
}

fn bench_supervisory(c: &mut Criterion, tally: &Tally) {
    let mut d = initialized_hand();
    for line in SUPERVISORY_LINES {
        let out = send(&mut d, line);
        assert!(out.ends_with(b"=> ") && !out.windows(3).any(|w| w == b"ERR"), "{}", String::from_utf8_lossy(&out));
    }
    let n = SUPERVISORY_LINES.len() as u64;
    let mut g = c.benchmark_group("device");
    g.throughput(Throughput::Elements(n));
    let mut out = Vec::with_capacity(256);
    g.bench_function("supervisory FSET/FGET/bh8-262", |b| {
        b.iter_custom(|iters| {
            timed(tally, iters, n, || {
                for line in SUPERVISORY_LINES {
                    let now = d.now();
                    d.handle_input(now, line);
                    d.drain_output(&mut out);
                    black_box(&out);
                    out.clear();
                }
            })
        })
    });
    g.finish();
}

fn bench_realtime(c: &mut Criterion, same_instant: &Tally, at_1khz: &Tally) {
    let mut g = c.benchmark_group("realtime");
    g.throughput(Throughput::Elements(2));
    for (name, tally, step) in [
        ("C blocks, 4 motors, all flags, same instant", same_instant, Duration::ZERO),
        ("C blocks, 4 motors, all flags, 1 ms apart", at_1khz, Duration::from_millis(1)),
    ] {
        let mut d = looping_hand();
        let (blocks, feedback_size) = control_blocks(&d);
        let mut now = d.now();
        for block in &blocks {
            now += step;
            d.handle_input(now, block);
            let out = d.take_output();
            assert_eq!((out.len(), out.first()), (feedback_size, Some(&b'*')), "one feedback block per C block");
        }
        let mut out = Vec::with_capacity(64);
        g.bench_function(name, |b| {
            b.iter_custom(|iters| {
                timed(tally, iters, 2, || {
                    for block in &blocks {
                        now += step;
                        d.handle_input(now, block);
                        d.drain_output(&mut out);
                        black_box(&out);
                        out.clear();
                    }
                })
            })
        });
    }
    g.finish();
}

/// Bytes allocated and not freed while `build` runs, with what it built (kept alive).
fn owned_heap<T>(build: impl FnOnce() -> T) -> (T, isize) {
    let region = Region::new(GLOBAL);
    let value = build();
    let s = region.change();
    (value, s.bytes_allocated as isize - s.bytes_deallocated as isize)
}

fn state_size() {
    let p = profile(); // the shared, cached profile: not the device's
    let device_size = std::mem::size_of::<Device>();
    let (fresh, fresh_heap) = owned_heap(|| Device::with_profile(p.clone()));
    let (looping, loop_heap) = owned_heap(looping_hand);
    let (profile_copy, profile_heap) =
        owned_heap(|| Profile::load_with("bh8-262-4.4.toml", &|f| embedded(f).map(str::to_string)));
    drop((fresh, looping, profile_copy));
    let kib = |b: isize| b as f64 / 1024.0;
    let aim = 64 * 1024;
    for (what, heap) in [("fresh (banner unread)", fresh_heap), ("after HI, flags set, in LOOP", loop_heap)] {
        let total = device_size as isize + heap;
        println!(
            "summary: device-state {what}: {:.1} KiB = size_of::<Device>() {device_size} B + owned heap {heap} B \
             (aim < 64 KiB: {})",
            kib(total),
            if total < aim { "met" } else { "MISSED" }
        );
    }
    println!(
        "summary: device-state shared profile bh8-262-4.4 (one Arc per process, not per device): {:.1} KiB heap",
        kib(profile_heap)
    );
}

fn report(name: &str, unit: &str, tally: &Tally, aim: f64) {
    if tally.elements.get() == 0 {
        return; // filtered out on the command line
    }
    let rate = tally.per_second();
    println!(
        "summary: {name}: {:.2} M {unit}/s over {} {unit} in {:.2} s, {:.2} allocations per {} (aim >= {:.1} M/s: {})",
        rate / 1e6,
        tally.elements.get(),
        tally.time.get().as_secs_f64(),
        tally.allocations_per_element(),
        unit.trim_end_matches('s'),
        aim / 1e6,
        if rate >= aim { "met" } else { "MISSED" }
    );
}

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    let mut c = Criterion::default().configure_from_args();
    let (parse, supervisory) = (Tally::default(), Tally::default());
    let (rt_same, rt_1khz) = (Tally::default(), Tally::default());
    bench_parse(&mut c, &parse);
    bench_supervisory(&mut c, &supervisory);
    bench_realtime(&mut c, &rt_same, &rt_1khz);
    c.final_summary();
    if !benching {
        // Test mode: every workload ran once and its checks passed; no figures.
        return;
    }
    println!();
    report("parse_line bh8-262 mix", "lines", &parse, 1e6);
    report("device supervisory FSET/FGET", "commands", &supervisory, 5e5);
    report("realtime C blocks 4 motors all flags, same instant", "blocks", &rt_same, 1e6);
    report("realtime C blocks 4 motors all flags, 1 kHz (physics tick each)", "blocks", &rt_1khz, 1e6);
    state_size();
}
