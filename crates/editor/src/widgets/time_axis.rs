//! The time axis the dope sheet and the curve editor share: a span of frames laid across a
//! span of screen points, mapped both ways, and zoomed or panned as both panels do it.

/// Frames `start`..`end` shown from `left` to `right` (screen points).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeAxis {
    /// Left and right ends of the axis, screen points.
    pub left: f32,
    pub right: f32,
    /// The frames shown at the left and right ends.
    pub start: f64,
    pub end: f64,
}

impl TimeAxis {
    /// The screen x of `frame`.
    #[must_use]
    pub fn x(&self, frame: f64) -> f32 {
        let span = (self.end - self.start).max(1e-9);
        self.left + ((frame - self.start) / span) as f32 * (self.right - self.left)
    }

    /// The frame at screen x `x` (fractional).
    #[must_use]
    pub fn frame(&self, x: f32) -> f64 {
        self.start + f64::from(x - self.left) * self.frames_per_point()
    }

    /// Frames per screen point.
    #[must_use]
    pub fn frames_per_point(&self) -> f64 {
        (self.end - self.start) / f64::from((self.right - self.left).max(1.0))
    }

    /// The frames shown after zooming by `factor` (above 1 zooms in) about the frame `anchor`,
    /// which stays where it is on screen; at least `min_span` frames stay in view.
    #[must_use]
    pub fn zoomed(&self, anchor: f64, factor: f64, min_span: f64) -> (f64, f64) {
        let span = ((self.end - self.start) / factor).max(min_span);
        let t = (anchor - self.start) / (self.end - self.start).max(1e-9);
        let start = anchor - t * span;
        (start, start + span)
    }

    /// The frames shown after the content moved `points` to the right (a drag or a wheel).
    #[must_use]
    pub fn panned(&self, points: f32) -> (f64, f64) {
        let shift = -f64::from(points) * self.frames_per_point();
        (self.start + shift, self.end + shift)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AXIS: TimeAxis = TimeAxis { left: 100.0, right: 300.0, start: 10.0, end: 50.0 };

    #[test]
    fn frames_and_points_map_both_ways() {
        // 40 frames over 200 points: 0.2 frames per point.
        assert_eq!(AXIS.frames_per_point(), 0.2);
        for (frame, x) in [(10.0, 100.0), (30.0, 200.0), (50.0, 300.0), (0.0, 50.0), (60.0, 350.0)] {
            assert_eq!(AXIS.x(frame), x, "frame {frame}");
            assert!((AXIS.frame(x) - frame).abs() < 1e-9, "x {x}");
        }
    }

    #[test]
    fn zoom_keeps_the_anchor_in_place_and_pan_follows_the_pointer() {
        let (start, end) = AXIS.zoomed(20.0, 2.0, 4.0);
        assert_eq!((start, end), (15.0, 35.0));
        let zoomed = TimeAxis { start, end, ..AXIS };
        assert_eq!(zoomed.x(20.0), AXIS.x(20.0), "the anchor stays under the pointer");
        assert_eq!(
            AXIS.zoomed(20.0, 100.0, 4.0).1 - AXIS.zoomed(20.0, 100.0, 4.0).0,
            4.0,
            "the shortest span"
        );
        // Content dragged 50 points right shows 10 frames earlier.
        assert_eq!(AXIS.panned(50.0), (0.0, 40.0));
        // A degenerate axis (no width, no span) maps without dividing by zero.
        let flat = TimeAxis { left: 5.0, right: 5.0, start: 3.0, end: 3.0 };
        assert!(flat.x(3.0).is_finite() && flat.frame(5.0).is_finite() && flat.frames_per_point() == 0.0);
    }
}
