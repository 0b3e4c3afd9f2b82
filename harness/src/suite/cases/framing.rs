//! Framing: echo, line endings, empty lines, line length, case, separators.

use super::*;

impl Gen {
    pub(super) fn framing(&mut self) {
        let p = self.p.clone();
        let c = self
            .case(
                "framing-echo",
                "Every byte of a line is echoed as sent; answers start with LF CR; the CR is not echoed",
            )
            .decision("framing-echo")
            .preamble(false)
            .line("FGET DP")
            .line("BOGUS")
            .line("FGET DP MCV");
        self.add(c);

        let c = self
            .case("framing-empty-line", "A bare CR, or separators then CR, prints a fresh prompt and no status")
            .decision("framing-empty-line")
            .preamble(false)
            .line("")
            .line("   ")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case(
                "framing-case",
                "Command words, parameter names and prefix letters are case-insensitive; the echo keeps the case",
            )
            .decision("framing-case")
            .preamble(false)
            .line("fget dp")
            .line("Fget Dp Mcv")
            .line("sfget dp")
            .line("gFGET dp")
            .line("fset dp 1234")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case(
                "framing-whitespace",
                "Runs of spaces and tabs separate tokens; leading separators and a space after the prefix are accepted",
            )
            .decision("framing-whitespace")
            .preamble(false)
            .line("  FGET   DP")
            .line("FGET\tDP")
            .line("12 FGET DP")
            .line("FGET DP   ");
        self.add(c);

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

        let c = self
            .case("framing-numbers", "Values are decimal integers only: hex, a plus sign, a fraction or a word is 128")
            .decision("framing-numbers")
            .preamble(false)
            .line("FSET DP 0x10")
            .line("FSET DP +5")
            .line("FSET DP 1.5")
            .line("FSET DP TRUE")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case("framing-errors-combine", "Problems in one line are OR'ed into one ERR")
            .decision("framing-errors-combine")
            .preamble(false)
            .line("FSET NOPE 1 DP 99999")
            .line("1FGET NOPE")
            .line("1FGET DP");
        self.add(c);

        let c = self
            .case("framing-line-atomic", "A line with an error changes nothing and prints no value line")
            .decision("framing-line-atomic")
            .decision("bh8-partial-errors")
            .preamble(false)
            .line("FSET DP 1234 MCV 99999")
            .line("FGET DP NOPE")
            .line("FGET DP MCV");
        self.add(c);

        let c = self
            .case("framing-backspace", "No line editing: backspace is an ordinary byte, echoed and kept")
            .decision("framing-backspace")
            .preamble(false)
            .raw(b"FGET DX\x08P\r")
            .line("FGET DP");
        self.add(c);

        let c = self
            .case("framing-busy-input", "A line sent while a command runs is echoed and run after the prompt")
            .decision("framing-busy-input")
            .preamble(true)
            .raw(b"GC\rFGET DP\r")
            .within(Duration::from_secs(30))
            .wait();
        self.add(c);

        let c = self
            .case("framing-abort-partial-line", "^C discards a partial line and prints a fresh prompt")
            .decision("framing-abort-idle")
            .preamble(false)
            .partial(b"FGET D")
            .abort()
            .line("P")
            .line("FGET DP");
        self.add(c);
    }
}
