//! The radio's messages on their way: each step's messages are sent at once and arrive
//! `delay` steps later (`radio.delay_s`, whole periods), all of them together; none arrive in
//! the first `delay` steps of a flight. Both engines keep one, so that a delayed radio is the
//! same in each. Buffers are reused from step to step.

use std::collections::VecDeque;

use super::measurement::Message;

/// The messages sent in the last steps and those arriving now.
#[derive(Debug, Default)]
pub struct Airwaves {
    /// Messages sent in the last `delay + 1` steps, oldest first (with a delay; without one,
    /// a spare buffer).
    history: VecDeque<Vec<Message>>,
    /// The messages arriving this step.
    arriving: Vec<Message>,
    /// How many were sent this step.
    sent: usize,
}

impl Airwaves {
    /// An empty buffer for this step's messages (one that has arrived already, reused).
    pub fn buffer(&mut self, delay: usize) -> Vec<Message> {
        let mut b = if self.history.len() > delay { self.history.pop_front() } else { None }.unwrap_or_default();
        b.clear();
        b
    }

    /// Sends `now` (from [`Self::buffer`]): what was sent `delay` steps ago arrives.
    pub fn send(&mut self, mut now: Vec<Message>, delay: usize) {
        self.sent = now.len();
        if delay == 0 {
            std::mem::swap(&mut self.arriving, &mut now);
            self.history.push_back(now);
            self.history.truncate(1);
        } else {
            self.history.push_back(now);
            self.arriving.clear();
            if self.history.len() == delay + 1 {
                if let Some(front) = self.history.front() {
                    self.arriving.extend_from_slice(front);
                }
            }
        }
    }

    /// The messages arriving this step, in the order they were sent.
    pub fn arriving(&self) -> &[Message] {
        &self.arriving
    }

    /// How many messages were sent this step.
    pub fn sent(&self) -> usize {
        self.sent
    }

    /// Nothing on the air (a flight's start: nothing of its warm-up arrives in it).
    pub fn clear(&mut self) {
        self.history.clear();
        self.arriving.clear();
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        let m = std::mem::size_of::<Message>();
        self.history.iter().map(|h| h.capacity() * m).sum::<usize>() + self.arriving.capacity() * m
    }
}
