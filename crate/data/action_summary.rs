/// Counts and sequence lengths of one action in a [`Summary`](super::Summary).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ActionSummary {
    /// Number of sequences.
    pub sequences: usize,
    /// Shortest sequence, in steps.
    pub min_len: usize,
    /// Longest sequence, in steps.
    pub max_len: usize,
    /// Steps over all sequences (for the mean).
    pub total_steps: usize,
}

impl ActionSummary {
    /// Account for one more sequence of `len` steps.
    pub fn add(&mut self, len: usize) {
        if self.sequences == 0 {
            self.min_len = len;
            self.max_len = len;
        } else {
            self.min_len = self.min_len.min(len);
            self.max_len = self.max_len.max(len);
        }
        self.sequences += 1;
        self.total_steps += len;
    }

    /// Mean sequence length in steps (0 with no sequence).
    pub fn mean_len(&self) -> f64 {
        if self.sequences == 0 {
            0.0
        } else {
            self.total_steps as f64 / self.sequences as f64
        }
    }
}
