//! When the time loop stops stepping: the next field output, contact
//! detection, finiteness check, checkpoint, settle check or progress tick.
//! Between two stops the steps run uninterrupted.

/// The cadences of a run, and the field outputs still to write.
#[derive(Debug, Clone)]
pub(super) struct Schedule {
    /// Last step.
    steps: u64,
    /// Field output steps after the start, ascending; `next_out` indexes the next.
    output_steps: Vec<u64>,
    next_out: usize,
    /// Contact detection every so many steps (0: once, before the first).
    detect_every: u64,
    /// Checkpoint every so many steps (0: only at the end).
    checkpoint_every: u64,
    /// Finiteness check of the temperatures every so many steps.
    check_every: u64,
    /// Progress bar update every so many steps.
    tick: u64,
    /// Stop after every step (particle statistics, settle check).
    every_step: bool,
    /// A history row every so many steps (0: only with the fields).
    history_every: u64,
}

impl Schedule {
    /// Steps between finiteness checks of the temperatures.
    pub const CHECK_EVERY: u64 = 1000;

    /// The schedule of a run of `steps` steps from `start_step`.
    pub fn new(
        steps: u64,
        output_steps: &[u64],
        start_step: u64,
        detect_every: u64,
        checkpoint_every: u64,
        every_step: bool,
    ) -> Schedule {
        Schedule {
            steps,
            output_steps: output_steps
                .iter()
                .copied()
                .filter(|&s| s > start_step)
                .collect(),
            next_out: 0,
            detect_every,
            checkpoint_every,
            check_every: Self::CHECK_EVERY,
            tick: (steps / 200).max(1),
            every_step,
            history_every: 0,
        }
    }

    /// Also stop for a history row every `n` steps (0: never).
    pub fn with_history_every(mut self, n: u64) -> Schedule {
        self.history_every = n;
        self
    }

    /// Whether a history row without fields is written at `step`.
    pub fn is_history(&self, step: u64) -> bool {
        self.history_every > 0 && step.is_multiple_of(self.history_every) && !self.is_output(step)
    }

    /// The next field output step, if any is left.
    fn next_output(&self) -> Option<u64> {
        self.output_steps.get(self.next_out).copied()
    }

    /// Run uninterrupted from `step` until the next output, check or
    /// progress tick (at most the last step).
    pub fn next_stop(&self, step: u64) -> u64 {
        let steps = self.steps;
        let next_detect = step
            .checked_div(self.detect_every)
            .map_or(steps, |k| (k + 1) * self.detect_every);
        [
            self.next_output().unwrap_or(steps),
            (step / self.check_every + 1) * self.check_every,
            (step / self.tick + 1) * self.tick,
            next_detect,
            if self.every_step { step + 1 } else { steps },
            step.checked_div(self.checkpoint_every)
                .map_or(steps, |k| (k + 1) * self.checkpoint_every),
            step.checked_div(self.history_every)
                .map_or(steps, |k| (k + 1) * self.history_every),
        ]
        .into_iter()
        .min()
        .unwrap_or(steps)
        .min(steps)
    }

    /// Whether fields are written at `step`.
    pub fn is_output(&self, step: u64) -> bool {
        self.next_output() == Some(step)
    }

    /// The next output was written (or the run stops).
    pub fn output_written(&mut self) {
        self.next_out += 1;
    }

    /// Whether contacts are detected again at `step` (not after the last step).
    pub fn is_detection(&self, step: u64) -> bool {
        self.detect_every > 0 && step.is_multiple_of(self.detect_every) && step < self.steps
    }

    /// Whether the temperatures are checked for finiteness at `step`.
    pub fn is_finite_check(&self, step: u64) -> bool {
        step.is_multiple_of(self.check_every) || self.is_output(step)
    }

    /// Whether a checkpoint is written at `step` (besides the last one).
    pub fn is_checkpoint(&self, step: u64) -> bool {
        self.checkpoint_every > 0 && step.is_multiple_of(self.checkpoint_every)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stops from `start` to the end.
    fn stops(s: &mut Schedule, start: u64) -> Vec<u64> {
        let mut step = start;
        let mut out = Vec::new();
        while step < s.steps {
            step = s.next_stop(step);
            out.push(step);
            if s.is_output(step) {
                s.output_written();
            }
        }
        out
    }

    #[test]
    fn stops_at_outputs_ticks_and_the_end() {
        // 400 steps: a progress tick every 2 steps, and the output at 5.
        let mut s = Schedule::new(400, &[0, 5, 400], 0, 0, 0, false);
        assert_eq!(s.next_stop(0), 2);
        assert_eq!(stops(&mut s, 0).len(), 201);
        // 10 000 steps: tick every 50, outputs at 75 and 10 000, checks every 1000.
        let mut s = Schedule::new(10_000, &[0, 75, 10_000], 0, 0, 0, false);
        let v = stops(&mut s, 0);
        assert_eq!(&v[..3], &[50, 75, 100]);
        assert_eq!(*v.last().unwrap(), 10_000);
        assert!(v.contains(&1000));
    }

    #[test]
    fn detection_and_checkpoint_cadence() {
        let s = Schedule::new(100_000, &[0, 100_000], 0, 30, 70, false);
        assert_eq!(s.next_stop(0), 30);
        assert_eq!(s.next_stop(30), 60);
        assert_eq!(s.next_stop(60), 70);
        assert!(s.is_detection(90) && !s.is_detection(91));
        assert!(s.is_checkpoint(140) && !s.is_checkpoint(141));
        // No detection after the last step.
        let s = Schedule::new(90, &[0, 90], 0, 30, 0, false);
        assert!(!s.is_detection(90));
        // Detection once (0): never again.
        let s = Schedule::new(90, &[0, 90], 0, 0, 0, false);
        assert!(!s.is_detection(0) && !s.is_checkpoint(0));
    }

    #[test]
    fn history_rows_between_outputs() {
        // 1000 steps, outputs at 0, 500, 1000, a history row every 3 steps.
        let s = Schedule::new(1000, &[0, 500, 1000], 0, 0, 0, false).with_history_every(3);
        assert_eq!(s.next_stop(0), 3);
        assert_eq!(s.next_stop(498), 500);
        assert!(s.is_history(3) && s.is_history(999) && !s.is_history(4));
        // Not at an output step: the output writes the row.
        let s = Schedule::new(1000, &[0, 300, 1000], 0, 0, 0, false).with_history_every(3);
        assert!(!s.is_history(300) && s.is_history(303));
    }

    #[test]
    fn every_step_and_restart() {
        let s = Schedule::new(100_000, &[0, 100_000], 0, 0, 0, true);
        assert_eq!(s.next_stop(7), 8);
        // A restart at 500 skips the outputs up to it.
        let mut s = Schedule::new(1000, &[0, 250, 500, 750, 1000], 500, 0, 0, false);
        assert!(!s.is_output(500));
        assert_eq!(s.next_output(), Some(750));
        assert!(s.is_finite_check(750) && s.is_finite_check(1000) && !s.is_finite_check(600));
        // An output not yet written holds the loop back; once written, the end.
        assert_eq!(s.next_stop(749), 750);
        s.output_written();
        assert_eq!(s.next_stop(999), 1000);
    }
}
