//! Framing: echo, line endings, empty lines, line length, case, separators. The cases are
//! scripts (`conformance/suite-cases/framing/`) except the line-length one, whose lines are filled
//! to the profile's limit.

use super::*;

impl Gen {
    pub(super) fn framing(&mut self) {
        let p = self.p.clone();
        self.scripts(&["framing-echo", "framing-empty-line", "framing-case", "framing-whitespace"]);

        let max = p.framing.max_line;
        let fits = fill_line("FGET", " DP", max);
        let over = format!("{fits}P");
        let c = self
            .case(
                "framing-max-line",
                format!("A line of {max} bytes is accepted; one byte more gives ERR {}", p.framing.overlong_status),
            )
            .decision("framing-max-line")
            .decision("framing-whitespace")
            .preamble(false)
            .line(&fits)
            .line(&over)
            .line("FGET DS");
        self.add(c);

        self.scripts(&[
            "framing-numbers",
            "framing-errors-combine",
            "framing-line-atomic",
            "framing-backspace",
            "framing-busy-input",
            "framing-abort-partial-line",
        ]);
    }
}
