//! Snapshots of the exact wire bytes of the seed's worked examples, one entry per exchange:
//! what the host sent and what the hand answered, both escaped with
//! [`gcl_model::escape::escape`]. The device runs with a fixed seed and no noise so that the
//! bytes are stable; time advances between RealTime blocks so that motion shows in LFDP.

use std::time::Duration;

use gcl_model::escape::escape;
use gcl_model::{Device, DeviceConfig, Scenario};

use crate::support;

/// A recorded conversation with a hand.
struct Transcript {
    device: Device,
    lines: Vec<String>,
}

impl Transcript {
    /// Powers a hand up and records its banner as the first exchange.
    fn new(profile: &str) -> Transcript {
        let scenario = Scenario { strain_noise: 0, temperature_noise: 0, ..Scenario::default() };
        let config = DeviceConfig { seed: 1, scenario, ..DeviceConfig::default() };
        let mut device = Device::new(support::profile(profile), config);
        let banner = device.take_output();
        let mut t = Transcript { device, lines: Vec::new() };
        t.record(b"", &banner);
        t
    }

    fn record(&mut self, sent: &[u8], received: &[u8]) {
        self.lines.push(format!("sent     \"{}\"", escape(sent)));
        self.lines.push(format!("received \"{}\"", escape(received)));
    }

    /// Sends bytes at the present time and runs any command they start to completion.
    fn send(&mut self, bytes: &[u8]) -> Vec<u8> {
        let out = support::exchange(&mut self.device, bytes);
        self.record(bytes, &out);
        out
    }

    /// Sends a command line (CR added).
    fn line(&mut self, line: &str) -> Vec<u8> {
        self.send(format!("{line}\r").as_bytes())
    }

    /// Lets simulated time pass with no input.
    fn wait(&mut self, ms: u64) {
        let t = self.device.now() + Duration::from_millis(ms);
        self.device.handle_timeout(t);
        assert!(self.device.output().is_empty(), "the hand spoke unasked");
    }

    fn text(&self) -> String {
        self.lines.join("\n")
    }
}

#[test]
fn seed_supervisory_example() {
    let mut t = Transcript::new("seed");
    assert_eq!(t.line("HI"), b"HI\n\r=> ");
    assert_eq!(t.line("123C"), b"123C\n\r=> ");
    assert_eq!(t.line("123O"), b"123O\n\r=> ");
    insta::assert_snapshot!(t.text());
}

/// The seed's RealTime example: fingers 1 and 2 send a velocity and report strain and delta
/// position, the spread reports delta position only.
fn realtime_example(t: &mut Transcript) {
    assert_eq!(t.line("HI"), b"HI\n\r=> ");
    t.line("12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1");
    t.line("4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1");
}

/// The blocks of the example after `124LOOP`; returns what each block got, in order.
fn realtime_blocks(t: &mut Transcript) -> Vec<Vec<u8>> {
    let mut got = Vec::new();
    // Velocity 50 for F1 and 30 for F2, with a full feedback block.
    got.push(t.send(&[b'C', 50, 30]));
    t.wait(10);
    // Velocity 40 and 20, acknowledged with `*` alone.
    got.push(t.send(&[b'c', 40, 20]));
    t.wait(10);
    got.push(t.send(b"A"));
    t.wait(10);
    got.push(t.send(b"a"));
    t.wait(10);
    got.push(t.send(b"\x03"));
    got
}

#[test]
fn seed_realtime_example() {
    let mut t = Transcript::new("seed");
    realtime_example(&mut t);
    assert_eq!(t.line("124LOOP"), b"124LOOP*");
    let got = realtime_blocks(&mut t);
    let lens: Vec<usize> = got.iter().map(Vec::len).collect();
    assert_eq!(lens, vec![6, 1, 6, 1, 5], "6-byte feedback blocks, `*` acks, then the prompt");
    assert!(got[0].starts_with(b"*") && got[2].starts_with(b"*"));
    assert_eq!(got[4], b"\n\r=> ");
    insta::assert_snapshot!(t.text());
}

#[test]
fn bh8_262_43_realtime_example_with_lft() {
    let mut t = Transcript::new("bh8-262-4.3");
    realtime_example(&mut t);
    assert_eq!(t.line("PSET LFT 1"), b"PSET LFT 1\n\r=> ");
    assert_eq!(t.line("124LOOP"), b"124LOOP*");
    let got = realtime_blocks(&mut t);
    let lens: Vec<usize> = got.iter().map(Vec::len).collect();
    assert_eq!(lens, vec![8, 1, 8, 1, 5], "8-byte feedback blocks end with a 2-byte temperature");
    // 31.5 C in tenths, high byte first.
    assert_eq!(got[0][6..], [0x01, 0x3B]);
    insta::assert_snapshot!(t.text());
}
