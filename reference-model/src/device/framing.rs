//! Framing: bytes in (echo, line assembly, the queue while a command runs) and lines out
//! (line endings, the prompt, `ERR n`, the banner). Events for [`super::Device::poll_event`]
//! are pushed here.

use super::*;

impl Device {
    pub(super) fn input_byte(&mut self, b: u8) {
        match std::mem::replace(&mut self.state, State::Idle) {
            State::Busy(task) => {
                if b == self.profile.framing.abort {
                    self.abort_task(task);
                } else {
                    self.state = State::Busy(task);
                    if self.queue.len() < 2 * self.profile.framing.max_line + 4 {
                        self.queue.push_back(b);
                    }
                }
            }
            State::Loop(rt) => self.loop_byte(rt, b),
            State::Idle => self.line_byte(b),
        }
    }

    /// Runs the input that arrived while a command ran, until the queue is empty or a queued
    /// command starts running in turn.
    pub(super) fn drain_queue(&mut self) {
        while !self.is_busy() {
            let Some(b) = self.queue.pop_front() else { break };
            self.input_byte(b);
        }
    }

    pub(super) fn line_byte(&mut self, b: u8) {
        let framing = &self.profile.framing;
        if b == framing.abort {
            self.line.clear();
            self.overflow = false;
            self.end_line(StatusBits::empty());
        } else if b == framing.terminator {
            let line = std::mem::take(&mut self.line);
            let overflow = std::mem::replace(&mut self.overflow, false);
            if overflow && !self.has(Fault::OverlongLineRuns) {
                self.end_line(StatusBits::from_bits_truncate(framing.overlong_status));
            } else {
                self.run_line(&line);
            }
            self.line = line;
            self.line.clear();
        } else {
            if framing.echo {
                self.out.push(b);
            }
            if self.line.len() < framing.max_line {
                self.line.push(b);
            } else {
                self.overflow = true;
            }
        }
    }

    pub(super) fn prompt(&mut self) {
        self.out.extend_from_slice(&self.eol);
        self.out.extend_from_slice(&self.prompt);
    }

    pub(super) fn print_line(&mut self, text: &str) {
        self.out.extend_from_slice(&self.eol);
        self.out.extend_from_slice(text.as_bytes());
    }

    /// Ends a command: the status line if any, then the prompt.
    pub(super) fn end_line(&mut self, status: StatusBits) {
        self.last_status = status;
        self.push_event(Event::LineDone(status));
        if !status.is_empty() {
            let text = format!("ERR {}", status.code());
            self.print_line(&text);
        }
        self.prompt();
    }

    pub(super) fn push_event(&mut self, e: Event) {
        if self.events.len() >= MAX_EVENTS {
            self.events.pop_front();
        }
        self.events.push_back(e);
    }

    pub(super) fn print_banner(&mut self) {
        self.push_event(Event::PoweredUp);
        let profile = self.profile.clone();
        for l in &profile.banner {
            self.print_line(l);
        }
        self.prompt();
    }
}
