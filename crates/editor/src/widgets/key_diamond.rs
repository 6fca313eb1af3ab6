//! A key diamond of the dope sheet, painted (the dope sheet hit-tests its rows itself).

use egui::{Color32, Painter, Pos2, Shape, Stroke, Vec2};

/// Half the diamond's width, points.
pub const DIAMOND_RADIUS: f32 = 5.5;

/// Paints a key diamond of half-width `radius` centred at `center` in `fill`; a selected key
/// gets a white outline.
pub fn paint_diamond(painter: &Painter, center: Pos2, radius: f32, fill: Color32, selected: bool) {
    let stroke = Stroke::new(1.0, if selected { Color32::WHITE } else { Color32::from_gray(60) });
    let points = vec![
        center + Vec2::new(0.0, -radius),
        center + Vec2::new(radius, 0.0),
        center + Vec2::new(0.0, radius),
        center + Vec2::new(-radius, 0.0),
    ];
    painter.add(Shape::convex_polygon(points, fill, stroke));
}
