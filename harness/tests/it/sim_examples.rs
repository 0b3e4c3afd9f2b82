//! Both example programs of the seed, end to end through the host library, on `gcl sim` over
//! a pty, TCP and stdio, and in-process.

use crate::sim_support;

use std::time::Duration;

use gcl_host::client::Hand;
use gcl_host::client::programs::{self, Clock};
use gcl_host::target::OpenOptions;
use sim_support::{ALL, start};

const RUN: Duration = Duration::from_millis(2500);

#[test]
fn supervisory_example_on_every_transport() {
    for t in ALL {
        let (_sim, mut hand) = start(t, "seed", &[]);
        let mut out = Vec::new();
        let r = programs::supervisory(&mut hand, &mut out).unwrap_or_else(|e| panic!("{t:?}: {e}"));
        assert!(r.banner.iter().any(|l| l.contains("BarrettHand Firmware")), "{t:?}");
        assert!(r.after_close.iter().all(|p| *p > 10_000), "{t:?}: {r:?}");
        assert!(r.after_open.iter().all(|p| *p < 100), "{t:?}: {r:?}");
    }
}

#[test]
fn realtime_example_agrees_on_every_transport() {
    let mut in_process = Hand::open(&"sim:seed".parse().unwrap(), &OpenOptions::default()).unwrap();
    let reference = programs::realtime(&mut in_process, Clock::Link, RUN, &mut Vec::new()).unwrap();
    assert!(
        reference.positions[0] > reference.positions[1] && reference.positions[1] > reference.positions[2],
        "{reference:?}"
    );
    let mut over_wire = Vec::new();
    for t in ALL {
        let (_sim, mut hand) = start(t, "seed", &["--time", "fast"]);
        let r = programs::realtime(&mut hand, Clock::Wire { baud: 9600 }, RUN, &mut Vec::new())
            .unwrap_or_else(|e| panic!("{t:?}: {e}"));
        // The hand's simulated clock and the host's wire clock agree: the same cascade as
        // in-process, within a block.
        assert!(r.iterations.abs_diff(reference.iterations) <= 1, "{t:?}: {r:?} vs {reference:?}");
        for i in 0..3 {
            assert!((r.positions[i] - reference.positions[i]).abs() <= 100, "{t:?}: {r:?} vs {reference:?}");
        }
        over_wire.push((t, r));
    }
    // Same bytes, same answers, whatever the transport.
    for (t, r) in &over_wire[1..] {
        assert_eq!(r, &over_wire[0].1, "{t:?} differs from {:?}", over_wire[0].0);
    }
}

#[test]
fn realtime_example_runs_on_bh8_262_in_process() {
    let mut hand = Hand::open(&"sim".parse().unwrap(), &OpenOptions::default()).unwrap();
    let r = programs::realtime(&mut hand, Clock::Link, Duration::from_secs(6), &mut Vec::new()).unwrap();
    assert!(r.started[0].is_some() && r.started[1].is_some(), "{r:?}");
}
