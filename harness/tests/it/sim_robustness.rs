//! Nothing a client does takes the simulated hand down: reopening the port, disconnecting
//! mid-command or mid-RealTime, garbage and overlong lines, on every transport.

use crate::sim_support;

use std::time::Duration;

use gcl_host::Link;
use gcl_host::client::{Hand, RtFlags};
use gcl_host::links::{ExecLink, StderrMode};
use sim_support::{ALL, SimProcess, Transport, noise, start, stdio_argv};

fn fresh(hand: &mut Hand) {
    hand.resync().unwrap();
    hand.command("HI").unwrap();
}

#[test]
fn reopening_keeps_the_hands_state() {
    for t in [Transport::Pty, Transport::Tcp] {
        let mut sim = SimProcess::start(t, &["--profile", "seed"]);
        {
            let mut a = sim.hand("seed");
            a.resync().unwrap();
            a.set("1", "DP", 1234).unwrap();
        }
        // Twice, so that the second client also finds the port reusable.
        for _ in 0..2 {
            let mut b = sim.hand("seed");
            b.resync().unwrap();
            assert_eq!(b.get("1", "DP").unwrap(), vec![1234], "{t:?}");
        }
        assert!(sim.running());
    }
}

#[test]
fn a_second_tcp_client_is_refused_while_one_is_connected() {
    let sim = SimProcess::start(Transport::Tcp, &["--profile", "seed"]);
    let mut a = sim.hand("seed");
    a.resync().unwrap();
    let mut b = sim.hand("seed");
    assert!(b.resync().is_err(), "the second connection must be closed");
    a.set("1", "DP", 777).unwrap();
    drop(a);
    let mut c = sim.hand("seed");
    c.resync().unwrap();
    assert_eq!(c.get("1", "DP").unwrap(), vec![777]);
}

#[test]
fn disconnecting_mid_command_leaves_the_hand_usable() {
    for t in [Transport::Pty, Transport::Tcp] {
        // Real time, so that the close is still moving when the client goes.
        let sim = SimProcess::start(t, &["--profile", "bh8-262", "--time", "real"]);
        {
            let mut a = sim.hand("bh8-262");
            fresh(&mut a);
            a.link_mut().send(b"C\r").unwrap();
        }
        {
            // Half a line, then gone.
            let mut b = sim.hand("bh8-262");
            b.link_mut().send(b"FGET D").unwrap();
        }
        let mut c = sim.hand("bh8-262");
        c.resync().unwrap_or_else(|e| panic!("{t:?}: {e}"));
        assert_eq!(c.get("1234", "P").unwrap().len(), 4, "{t:?}");
        assert_eq!(c.get("1", "DP").unwrap().len(), 1, "{t:?}");
    }
    // stdio: end of input mid-command ends the simulator cleanly.
    let mut link = ExecLink::spawn(&stdio_argv(&["--profile", "seed", "--time", "real"]), StderrMode::Null).unwrap();
    link.send(b"HI\rC\r").unwrap();
    link.close_input();
    assert_eq!(link.wait_exit(Duration::from_secs(30)), Some(0));
}

#[test]
fn disconnecting_mid_realtime_leaves_the_hand_usable() {
    for t in [Transport::Pty, Transport::Tcp] {
        let sim = SimProcess::start(t, &["--profile", "seed"]);
        {
            let mut a = sim.hand("seed");
            fresh(&mut a);
            a.rt_set_flags("123", RtFlags::barrett(1, 1, 0, 0, 1, 0, 1, 0, 1)).unwrap();
            a.rt_start("123").unwrap();
            a.rt_set_velocity('1', 40).unwrap();
            for _ in 0..5 {
                a.rt_update().unwrap();
            }
            // Half a control block, then gone.
            a.link_mut().send(b"C\x10").unwrap();
        }
        let mut b = sim.hand("seed");
        b.resync().unwrap();
        assert!(b.get("1", "P").unwrap()[0] > 0, "{t:?}");
        // And RealTime works again.
        b.rt_start("123").unwrap();
        b.rt_update().unwrap();
        b.rt_abort().unwrap();
    }
    let mut link = ExecLink::spawn(&stdio_argv(&["--profile", "seed"]), StderrMode::Null).unwrap();
    link.send(b"HI\r123LOOP\rC\x10").unwrap();
    link.close_input();
    assert_eq!(link.wait_exit(Duration::from_secs(30)), Some(0));
}

#[test]
fn garbage_then_a_command_still_works() {
    for t in ALL {
        let (mut sim, mut hand) = start(t, "seed", &[]);
        hand.resync().unwrap();
        for seed in 0..4 {
            let mut junk = noise(seed, 3000);
            // Never a line that moves or loops by chance: no CR inside, one at the end.
            junk.retain(|b| *b != b'\r');
            junk.push(b'\r');
            hand.link_mut().send(&junk).unwrap();
            hand.resync().unwrap_or_else(|e| panic!("{t:?} seed {seed}: {e}"));
            assert_eq!(hand.get("1", "DP").unwrap(), vec![1000], "{t:?}");
        }
        // An overlong line is refused, not fatal.
        let long = "X".repeat(10_000);
        hand.link_mut().send(long.as_bytes()).unwrap();
        hand.resync().unwrap();
        assert!(hand.command(&"FGET DP ".repeat(20)).is_err());
        assert_eq!(hand.get("4", "DP").unwrap(), vec![150]);
        if let Some(s) = &mut sim {
            assert!(s.running());
        }
    }
}

#[test]
fn real_time_motion_takes_time_and_ctrl_c_stops_it() {
    for t in ALL {
        let (_sim, mut hand) = start(t, "bh8-262", &["--time", "real"]);
        fresh(&mut hand);
        // The slowest close: about 4 s to the stop.
        hand.set("123", "MCV", 16).unwrap();
        hand.start("C").unwrap();
        let lines = hand.abort().unwrap();
        assert_eq!(lines, vec!["ERR 16384".to_string()], "{t:?}");
        let p = hand.get("1", "P").unwrap()[0];
        assert!(p < 17_000, "{t:?}: the close must have been stopped short, at {p}");
        // start + finish: a close, waited for (at the default speed).
        hand.set("1", "MCV", 100).unwrap();
        hand.start("1C").unwrap();
        hand.finish().unwrap();
        assert!(hand.get("1", "P").unwrap()[0] > 16_000, "{t:?}");
    }
}

#[test]
fn a_vanished_simulator_is_a_disconnect() {
    for t in [Transport::Pty, Transport::Tcp] {
        let mut sim = SimProcess::start(t, &["--profile", "seed"]);
        let mut hand = sim.hand("seed");
        hand.resync().unwrap();
        sim.kill();
        let e = hand.command("FGET DP").unwrap_err();
        assert!(matches!(e, gcl_host::client::ClientError::Link(gcl_host::LinkError::Disconnected)), "{t:?}: {e}");
    }
    let mut link = ExecLink::spawn(&stdio_argv(&["--profile", "seed"]), StderrMode::Null).unwrap();
    let pid = nix::unistd::Pid::from_raw(link.pid() as i32);
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGKILL).unwrap();
    let mut buf = Vec::new();
    let r = link.recv_until(&mut buf, Duration::from_secs(10), &|_| false);
    assert!(matches!(r, Err(gcl_host::LinkError::Disconnected)), "{r:?}");
}
