//! The outliner: objects (with their skeleton as an indented tree) and lights. Clicking
//! selects.

use egui::Ui;
use keyrig_core::Skeleton;

use crate::app::EditorApp;
use crate::session::Selected;

/// Indentation per tree level, points.
const INDENT: f32 = 14.0;

pub fn ui(ui: &mut Ui, app: &mut EditorApp) {
    egui::Panel::left("outliner").resizable(true).default_size(190.0).show_inside(ui, |ui| {
        ui.heading("Outliner");
        egui::ScrollArea::vertical().show(ui, |ui| {
            let mut clicked = None;
            let scene = app.doc.scene();
            for (o, object) in scene.objects.iter().enumerate() {
                let selected = app.session.selection.item == Some(Selected::Object(o));
                if ui.selectable_label(selected, object.name.as_str()).clicked() {
                    clicked = Some(Selected::Object(o));
                }
                if let Some(skeleton) = &object.skeleton {
                    for j in depth_first(skeleton) {
                        let item = Selected::Joint { object: o, joint: j };
                        ui.horizontal(|ui| {
                            ui.add_space(INDENT * (1 + depth(skeleton, j)) as f32);
                            let selected = app.session.selection.item == Some(item);
                            if ui.selectable_label(selected, skeleton.joints[j].name.as_str()).clicked() {
                                clicked = Some(item);
                            }
                        });
                    }
                }
            }
            ui.separator();
            for (l, light) in scene.lights.iter().enumerate() {
                let selected = app.session.selection.item == Some(Selected::Light(l));
                if ui.selectable_label(selected, light.name.as_str()).clicked() {
                    clicked = Some(Selected::Light(l));
                }
            }
            if let Some(item) = clicked {
                app.session.selection.item = Some(item);
            }
        });
    });
}

/// Depth of joint `j` (0 for a root). Parents with an index not below the child's are treated
/// as roots, so a broken file cannot loop.
fn depth(skeleton: &Skeleton, j: usize) -> usize {
    let mut d = 0;
    let mut current = j;
    while let Some(p) = skeleton.joints[current].parent.filter(|&p| p < current) {
        d += 1;
        current = p;
    }
    d
}

/// Joint indices in depth-first order (children follow their parent).
fn depth_first(skeleton: &Skeleton) -> Vec<usize> {
    let n = skeleton.joints.len();
    let mut out = Vec::with_capacity(n);
    let mut stack: Vec<usize> =
        (0..n).rev().filter(|&j| skeleton.joints[j].parent.is_none_or(|p| p >= j)).collect();
    while let Some(j) = stack.pop() {
        out.push(j);
        stack.extend((j + 1..n).rev().filter(|&c| skeleton.joints[c].parent == Some(j)));
    }
    out
}
