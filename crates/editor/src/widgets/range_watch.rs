//! Views that follow the frame range: the dope sheet and the curve editor remember the document
//! and frame range they were last laid out for, and refit their time axis (as *View all* or
//! *Fit*) when the range grew — an import that extends the range to cover its animation, a
//! longer range typed in the timeline — or another document was opened. A range that shrank
//! or stayed leaves a zoomed view alone: the refit never fights the animator's own zoom.

use keyrig_core::FrameRange;

/// The document and frame range a time view last saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RangeWatch {
    seen: Option<(u64, FrameRange)>,
}

impl RangeWatch {
    /// Notes the document `doc` (its id) and its `range` as laid out now; true when the view
    /// should refit: the range reaches past the one seen last (on either side) or the
    /// document is another one. The first look refits nothing (the view starts fitted).
    pub fn grew(&mut self, doc: u64, range: FrameRange) -> bool {
        let refit = match self.seen {
            None => false,
            Some((seen_doc, seen)) => seen_doc != doc || range.start < seen.start || range.end > seen.end,
        };
        self.seen = Some((doc, range));
        refit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_grown_range_or_another_document_refits() {
        let mut watch = RangeWatch::default();
        let range = |start, end| FrameRange { start, end };
        assert!(!watch.grew(1, range(0, 90)), "the first look keeps the view");
        assert!(!watch.grew(1, range(0, 90)), "nothing changed");
        assert!(watch.grew(1, range(0, 593)), "an import extended the range");
        assert!(!watch.grew(1, range(0, 90)), "undo shrank it: a zoom stays");
        assert!(watch.grew(1, range(-10, 90)), "an earlier start grows it too");
        assert!(!watch.grew(1, range(-10, 90)));
        assert!(watch.grew(2, range(0, 10)), "another document");
    }
}
