//! The page of a run of the seed's RealTime example program (`cargo run --example realtime --
//! --plot FILE`): hundreds of blocks, the fingers closing in turn. Each finger's position per
//! block is drawn over the band the reference model gives for the same program (its own run
//! in-process, ± a tolerance), the velocities sent below, and the first block where a finger
//! leaves its band is marked. In the one page design, self-contained.

use gcl_host::client::programs::RealtimeReport;

use super::page::Page;
use super::page::esc;
use super::svg::{Band, Plot, Series};

/// Counts a finger may be off the model's position at the same block: what the examples'
/// tests hold every transport to (`sim_examples`).
pub const POSITION_TOLERANCE: i64 = 100;

/// The first block (from 1) where each finger's position leaves the model's band, over the
/// blocks both runs have.
pub fn first_outside(run: &RealtimeReport, model: &RealtimeReport, tolerance: i64) -> [Option<usize>; 3] {
    [0, 1, 2].map(|m| {
        run.blocks
            .iter()
            .zip(&model.blocks)
            .position(|(a, g)| (a.positions[m] - g.positions[m]).abs() > tolerance)
            .map(|i| i + 1)
    })
}

/// The first block (from 1) at which a finger was sent a velocity other than 0.
fn starts(run: &RealtimeReport, m: usize) -> Option<usize> {
    run.blocks.iter().position(|b| b.velocities[m] != 0).map(|i| i + 1)
}

/// The page of `run` on `target` against `model`, the reference model's run of the same
/// program for the same time.
/// `options` are those given to the example (name without dashes, value).
pub fn realtime_program_page(
    target: &str,
    profile: &str,
    options: &[(String, String)],
    run: &RealtimeReport,
    model: &RealtimeReport,
) -> String {
    let tol = POSITION_TOLERANCE;
    let outside = first_outside(run, model, tol);
    let ok = outside.iter().all(Option::is_none) && run.blocks.len().abs_diff(model.blocks.len()) <= 1;
    let when = |m: usize| starts(run, m).map_or("never".to_string(), |b| format!("at block {b}"));
    let headline = format!(
        "{} blocks in {:.2} s; F2 started {}, F3 {}; {}",
        run.blocks.len(),
        run.elapsed.as_secs_f64(),
        when(1),
        when(2),
        if ok {
            format!("every finger stayed within {tol} counts of the reference model at every block")
        } else {
            let parts: Vec<String> = outside
                .iter()
                .enumerate()
                .filter_map(|(m, b)| b.map(|b| format!("F{} left the model's band at block {b}", m + 1)))
                .collect();
            if parts.is_empty() {
                format!("the model ran {} blocks in the same time", model.blocks.len())
            } else {
                parts.join(", ")
            }
        }
    );
    let mut p = Page::new(
        &format!("gcl example realtime on {target}"),
        ok,
        if ok { "AGREES WITH THE MODEL" } else { "PARTS FROM THE MODEL" },
        &headline,
    );
    p.facts(&[
        ("target".into(), format!("<code>{}</code>", esc(target))),
        ("profile".into(), esc(profile)),
        ("program".into(), "the seed's RealTime Mode Example Program: <code>RTSetFlags(\"123\",1,1,0,0,1,0,1,0,1)</code>, <code>123LOOP</code>; F1 closes at velocity 55, F2 starts when F1 passes 5000, F3 when F2 passes 5000".into()),
        ("the band".into(), format!("the reference model's run of the same program for the same time (in-process, simulated clock), ± {tol} counts at each block")),
        ("final positions".into(), esc(&format!("{:?} (FGET P after the loop)", run.final_positions))),
    ]);
    p.options(options);
    p.heading("positions", "Each finger's position per block");
    p.push("<p>The example's feedback carries positions only (LFAP 1; LFV 0 and LFS 0), so the hand sends no velocity or strain to plot: the velocities below are those the program sent.</p>\n");
    for (m, out) in outside.iter().enumerate() {
        let plot = Plot {
            title: format!("F{} position per block (LFAP, counts)", m + 1),
            x_label: "block".into(),
            y_label: "counts".into(),
            series: vec![Series {
                name: format!("F{} as the hand said", m + 1),
                points: run.blocks.iter().enumerate().map(|(i, b)| ((i + 1) as f64, b.positions[m] as f64)).collect(),
                ..Default::default()
            }],
            bands: vec![Band {
                points: model
                    .blocks
                    .iter()
                    .enumerate()
                    .map(|(i, b)| ((i + 1) as f64, (b.positions[m] - tol) as f64, (b.positions[m] + tol) as f64))
                    .collect(),
            }],
            marks: out.map(|b| vec![(b as f64, "leaves the band".to_string())]).unwrap_or_default(),
            band_label: Some(format!("the model's run ± {tol}")),
            ..Default::default()
        };
        p.push(&plot.to_svg(&format!("example-realtime-F{}-position", m + 1)));
    }
    p.heading("velocities", "The velocities sent per block");
    let plot = Plot {
        title: "Velocity sent per block (LCV)".into(),
        x_label: "block".into(),
        y_label: "velocity".into(),
        series: (0..3)
            .map(|m| Series {
                name: format!("F{}", m + 1),
                points: run.blocks.iter().enumerate().map(|(i, b)| ((i + 1) as f64, b.velocities[m] as f64)).collect(),
                steps: true,
                dots: false,
            })
            .collect(),
        marks: (1..3).filter_map(|m| starts(run, m).map(|b| (b as f64, format!("F{} starts", m + 1)))).collect(),
        ..Default::default()
    };
    p.push(&plot.to_svg("example-realtime-velocity"));
    p.push("<p class=\"muted\">Once a finger starts, its line lies on F1's: the marks say where each began.</p>\n");
    p.finish()
}
