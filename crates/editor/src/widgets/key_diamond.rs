//! A key diamond of the dope sheet: a clickable, draggable rhombus at a key's time.

use egui::{Color32, Pos2, Response, Sense, Shape, Stroke, Ui, Vec2, WidgetInfo, WidgetType};

/// Half the diamond's width, points.
pub const DIAMOND_RADIUS: f32 = 5.5;

/// Draws a key diamond centred at `center` and returns its response (click, drag, hover).
/// `label` is what accessibility tools and UI tests see ("key Elbow rotation frame 15").
pub fn key_diamond_ui(ui: &mut Ui, id: egui::Id, center: Pos2, selected: bool, label: &str) -> Response {
    let rect = egui::Rect::from_center_size(center, Vec2::splat(DIAMOND_RADIUS * 2.0 + 2.0));
    let response = ui.interact(rect, id, Sense::click_and_drag());
    let label_owned = label.to_owned();
    response.widget_info(|| WidgetInfo::selected(WidgetType::Button, true, selected, &label_owned));
    if ui.is_rect_visible(rect) {
        let r = if response.hovered() { DIAMOND_RADIUS + 1.0 } else { DIAMOND_RADIUS };
        let fill = if selected { Color32::from_rgb(255, 200, 60) } else { Color32::from_gray(200) };
        let stroke = Stroke::new(1.0, if selected { Color32::WHITE } else { Color32::from_gray(60) });
        let points = vec![
            center + Vec2::new(0.0, -r),
            center + Vec2::new(r, 0.0),
            center + Vec2::new(0.0, r),
            center + Vec2::new(-r, 0.0),
        ];
        ui.painter().add(Shape::convex_polygon(points, fill, stroke));
    }
    response
}
