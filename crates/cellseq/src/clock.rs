//! Deadlines: the wall-clock end of a run as one value that long computations below the
//! solvers (bounds, table builds, constructions) can check without a solver's context.
//!
//! A [`Deadline`] is a point in time or none at all; [`Deadline::passed`] reads the clock
//! (tens of nanoseconds), so a loop whose single step is cheap checks it every few thousand
//! steps ([`Ticker`]). A computation cut off by its deadline returns what it has when that is
//! still valid (a lower bound from fewer subgradient steps) and nothing otherwise.

use std::time::{Duration, Instant};

/// The end of a run's wall-clock budget, or none.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Deadline(Option<Instant>);

impl Deadline {
    /// No deadline: [`Deadline::passed`] is always false.
    pub const NONE: Deadline = Deadline(None);

    /// The deadline at `t`.
    pub fn at(t: Instant) -> Deadline {
        Deadline(Some(t))
    }

    /// `limit` from now (none without a limit, or when now + `limit` is beyond the clock's
    /// range).
    pub fn after(limit: Option<Duration>) -> Deadline {
        Deadline::from(Instant::now(), limit)
    }

    /// `limit` after `start` (none without a limit, or when it is beyond the clock's range).
    pub fn from(start: Instant, limit: Option<Duration>) -> Deadline {
        Deadline(limit.and_then(|l| start.checked_add(l)))
    }

    /// The instant, if there is one.
    pub fn instant(self) -> Option<Instant> {
        self.0
    }

    /// True when there is a deadline.
    pub fn is_set(self) -> bool {
        self.0.is_some()
    }

    /// True when the deadline has passed.
    #[inline]
    pub fn passed(self) -> bool {
        self.0.is_some_and(|t| Instant::now() >= t)
    }

    /// The time left (zero once passed), or `None` without a deadline.
    pub fn remaining(self) -> Option<Duration> {
        self.0.map(|t| t.saturating_duration_since(Instant::now()))
    }

    /// The earlier of the two.
    pub fn min(self, other: Deadline) -> Deadline {
        match (self.0, other.0) {
            (Some(a), Some(b)) => Deadline(Some(a.min(b))),
            (a, b) => Deadline(a.or(b)),
        }
    }

    /// `share` of the time left from now (`share` in [0, 1]); none without a deadline.
    pub fn share(self, share: f64) -> Deadline {
        match self.remaining() {
            Some(r) => Deadline::after(Some(r.mul_f64(share.clamp(0.0, 1.0)))),
            None => Deadline::NONE,
        }
    }
}

/// A deadline checked every `every`-th step of a loop whose steps are too cheap to read the
/// clock each time; once passed it stays passed.
#[derive(Debug, Clone)]
pub struct Ticker {
    deadline: Deadline,
    every: u32,
    count: u32,
    passed: bool,
}

impl Ticker {
    /// Checks `deadline` on every `every`-th call of [`Ticker::passed`] (and on the first).
    pub fn new(deadline: Deadline, every: u32) -> Ticker {
        Ticker {
            deadline,
            every: every.max(1),
            count: 0,
            passed: false,
        }
    }

    /// True once the deadline is seen to have passed.
    #[inline]
    pub fn passed(&mut self) -> bool {
        if !self.passed && self.deadline.is_set() {
            if self.count == 0 {
                self.passed = self.deadline.passed();
                self.count = self.every;
            }
            self.count -= 1;
        }
        self.passed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_deadline_never_passes_and_a_past_one_has_passed() {
        assert!(!Deadline::NONE.passed());
        assert_eq!(Deadline::NONE.remaining(), None);
        let past = Deadline::after(Some(Duration::ZERO));
        assert!(past.passed());
        assert_eq!(past.remaining(), Some(Duration::ZERO));
        let later = Deadline::after(Some(Duration::from_secs(3600)));
        assert!(!later.passed());
        assert_eq!(later.min(past), past);
        assert_eq!(Deadline::NONE.min(later), later);
        assert!(later.share(0.0).remaining().unwrap() <= Duration::from_millis(1));
        // beyond the clock's range: no deadline rather than a panic
        assert_eq!(Deadline::after(Some(Duration::MAX)), Deadline::NONE);
    }

    #[test]
    fn a_ticker_reads_the_clock_every_few_steps() {
        let mut t = Ticker::new(Deadline::after(Some(Duration::ZERO)), 100);
        assert!(t.passed());
        let mut t = Ticker::new(Deadline::after(Some(Duration::from_secs(3600))), 3);
        assert!((0..10).all(|_| !t.passed()));
        let mut t = Ticker::new(Deadline::NONE, 1);
        assert!(!t.passed());
    }
}
