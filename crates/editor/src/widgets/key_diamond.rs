//! A key diamond of the dope sheet, painted (the dope sheet hit-tests its rows itself), and the
//! look of each key type ([`KeyType`]): a keyframe is the plain diamond, a breakdown a small
//! blue one, a moving hold a dark grey one, an extreme a large rose one (Blender's shapes and
//! colours, so an animator reads them at a glance).

use egui::{Color32, Painter, Pos2, Shape, Stroke, Vec2};
use keyrig_core::KeyType;

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

/// How much larger or smaller than a keyframe's a key type's diamond is drawn.
#[must_use]
pub fn type_scale(key_type: KeyType) -> f32 {
    match key_type {
        KeyType::Keyframe => 1.0,
        KeyType::Breakdown => 0.7,
        KeyType::MovingHold => 0.8,
        KeyType::Extreme => 1.2,
    }
}

/// The fill of a key of `key_type` that is not a keyframe, lighter when selected; `None` for a
/// keyframe (the dope sheet's own grey, or yellow when selected).
#[must_use]
pub fn type_fill(key_type: KeyType, selected: bool) -> Option<Color32> {
    let (normal, light) = match key_type {
        KeyType::Keyframe => return None,
        KeyType::Breakdown => (Color32::from_rgb(90, 180, 235), Color32::from_rgb(170, 225, 255)),
        KeyType::MovingHold => (Color32::from_gray(115), Color32::from_rgb(210, 200, 150)),
        KeyType::Extreme => (Color32::from_rgb(225, 105, 130), Color32::from_rgb(255, 175, 190)),
    };
    Some(if selected { light } else { normal })
}
