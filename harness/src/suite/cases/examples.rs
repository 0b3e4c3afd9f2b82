//! The seed document's two example programs.

use super::*;

impl Gen {
    pub(super) fn examples(&mut self) {
        let mut k = self
            .case(
                "example-realtime-seed",
                "The seed's RealTime example: 124LOOP, 3-byte control blocks, 6-byte feedback blocks",
            )
            .clause("seed: RealTime Control, Example")
            .requires(Requirement::Realtime)
            .level(Level::Must);
        k = k.decision("seed-rt-feedback-order");
        let moving = vec![
            FieldRule { motor: Some(1), name: "LFDP", range: Some((0, 127)) },
            FieldRule { motor: Some(2), name: "LFDP", range: Some((-128, 0)) },
        ];
        let mut k = k.preamble(true);
        if self.p.params.iter().any(|x| x.name == "LFT") {
            k = k.line("PSET LFT 0");
        }
        let k = k
            .line("12FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFS 1 LFAP 0 LFDP 1 LFDPC 1")
            .line("4FSET LCV 0 LCVC 1 LCPG 0 LFV 0 LFS 0 LFAP 0 LFDP 1 LFDPC 1")
            .line("124LOOP")
            .block(&[0x43, 0x14, 0xFB], Shape::Block(Vec::new()))
            .block(&[0x43, 0x14, 0xFB], Shape::Block(moving.clone()))
            .block(&[0x43, 0x00, 0x00], Shape::Block(moving))
            .abort();
        self.add(k);

        let finger = self.limit(1);
        let moving = vec![
            FieldRule { motor: Some(1), name: "LFAP", range: Some((0, finger)) },
            FieldRule { motor: Some(2), name: "LFAP", range: Some((0, self.mpe(2))) },
            FieldRule { motor: Some(3), name: "LFAP", range: Some((0, self.mpe(3))) },
        ];
        let mut k = self
            .case(
                "example-realtime-program",
                "The seed's RealTime example program: RTSetFlags, 123LOOP, 4-byte C blocks, 7-byte feedback",
            )
            .clause("seed: Example Programs, RealTime Mode Example Program")
            .requires(Requirement::Realtime)
            .level(Level::Must)
            .preamble(true)
            .line("123FSET LCV 1 LCVC 1 LCPG 0 LFV 0 LFVC 1 LFS 0 LFAP 1 LFDP 0 LFDPC 1")
            .line("123LOOP");
        for _ in 0..5 {
            k = k.block(&[0x43, 55, 0, 0], Shape::Block(moving.clone()));
        }
        let k = k.abort().line("FGET DP");
        self.add(k);

        let mut k = self
            .case("example-supervisory-program", "The seed's supervisory example program: CR, RESET, HI, 123C, 123O")
            .clause("seed: Example Programs, Supervisory Mode Example Program")
            .decision("framing-empty-line")
            .level(Level::Must)
            .requires(Requirement::Motion)
            .comment("a host's start-up: ^C, a bare CR, RESET")
            .abort()
            .line("")
            .line_shaped("RESET", Shape::Banner)
            .line("FDEF");
        if self.has_cmd("PDEF") {
            k = k.line("PDEF");
        }
        let k = k.line("HI").line("123C").line("123O").get("", &["P"], Some(self.near([0; 4])));
        self.add(k);
    }
}
