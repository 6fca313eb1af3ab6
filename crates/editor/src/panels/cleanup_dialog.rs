//! Edit ▸ Reduce keys… and Smooth keys… (docs/cleanup.md): a small window with the
//! tolerances or the cutoff; Apply cleans the channels of the selected keys, else the keyed
//! channels of the selected object (a joint's skeleton object), else every keyed channel of
//! the scene, as one undo step ([`SceneEdit::ReduceKeys`], [`SceneEdit::SmoothKeys`]).

use egui::Context;
use keyrig_core::Scene;
use keyrig_edit::channels::ChannelId;
use keyrig_edit::cleanup::{butterworth_lowpass, key_total, keyed_channels, ReduceTolerance};
use keyrig_edit::SceneEdit;

use crate::actions::{Actions, Edit};
use crate::context::FrameCtx;
use crate::session::{Selected, Session};

/// Which clean-up the window is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CleanupMode {
    Reduce,
    Smooth,
}

/// The window's fields, kept while the editor runs.
pub struct CleanupDialog {
    /// Open, and for which clean-up.
    pub open: Option<CleanupMode>,
    pub tolerance: ReduceTolerance,
    pub cutoff_hz: f64,
}

impl Default for CleanupDialog {
    fn default() -> Self {
        CleanupDialog { open: None, tolerance: ReduceTolerance::DEFAULT, cutoff_hz: 6.0 }
    }
}

/// The channels a clean-up acts on (module documentation) and what they are called.
#[must_use]
pub fn target_channels(scene: &Scene, session: &Session) -> (Vec<ChannelId>, String) {
    let keys = &session.selection.keys;
    if !keys.is_empty() {
        let ids: std::collections::BTreeSet<ChannelId> = keys.iter().map(|k| k.channel).collect();
        return (ids.into_iter().collect(), "the selected keys' channels".to_owned());
    }
    let object = match session.selection.item {
        Some(Selected::Object(o) | Selected::Joint { object: o, .. }) if o < scene.objects.len() => Some(o),
        _ => None,
    };
    match object {
        Some(o) => (keyed_channels(scene, Some(&[o])), format!("{}'s keyed channels", scene.objects[o].name)),
        None => (keyed_channels(scene, None), "every keyed channel of the scene".to_owned()),
    }
}

impl CleanupDialog {
    /// The window, while a command opened it.
    pub fn ui(&mut self, ctx: &Context, frame: &FrameCtx<'_>, actions: &mut Actions) {
        let Some(mode) = self.open else { return };
        let scene = frame.doc.scene();
        let (channels, what) = target_channels(scene, frame.session);
        let title = match mode {
            CleanupMode::Reduce => "Reduce keys",
            CleanupMode::Smooth => "Smooth keys",
        };
        let mut open = true;
        let mut apply = false;
        egui::Window::new(title)
            .open(&mut open)
            .resizable(false)
            .collapsible(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                ui.label(format!(
                    "{}: {} channels, {} keys",
                    what,
                    channels.len(),
                    key_total(scene, &channels)
                ));
                let valid = match mode {
                    CleanupMode::Reduce => {
                        egui::Grid::new("cleanup_fields").num_columns(2).show(ui, |ui| {
                            ui.label("Angle (°)");
                            ui.add(egui::DragValue::new(&mut self.tolerance.angle_deg).speed(0.01).range(0.0..=180.0))
                                .on_hover_text("Largest angle between a reduced rotation and the original");
                            ui.end_row();
                            ui.label("Distance");
                            ui.add(egui::DragValue::new(&mut self.tolerance.distance).speed(0.0001).range(0.0..=1e6))
                                .on_hover_text("Largest distance of a reduced position, in scene units (0.001 = 1 mm in metres)");
                            ui.end_row();
                            ui.label("Value");
                            ui.add(egui::DragValue::new(&mut self.tolerance.value).speed(0.0001).range(0.0..=1e6))
                                .on_hover_text("Largest difference of any other value (scale, colour, scalars)");
                            ui.end_row();
                        });
                        self.tolerance.check().is_ok()
                    }
                    CleanupMode::Smooth => {
                        ui.horizontal(|ui| {
                            ui.label("Cutoff (Hz)");
                            ui.add(
                                egui::DragValue::new(&mut self.cutoff_hz)
                                    .speed(0.1)
                                    .range(0.01..=(scene.fps / 2.0 - 0.01).max(0.01)),
                            )
                            .on_hover_text("Motion faster than this is filtered out (Butterworth, forwards and backwards)");
                        });
                        butterworth_lowpass(self.cutoff_hz, scene.fps).is_ok()
                    }
                };
                ui.horizontal(|ui| {
                    if ui.add_enabled(valid && !channels.is_empty(), egui::Button::new("Apply")).clicked() {
                        apply = true;
                    }
                    if ui.button("Cancel").clicked() {
                        self.open = None;
                    }
                });
            });
        if apply {
            let edit = match mode {
                CleanupMode::Reduce => SceneEdit::ReduceKeys { channels, tolerance: self.tolerance },
                CleanupMode::Smooth => SceneEdit::SmoothKeys { channels, cutoff_hz: self.cutoff_hz },
            };
            actions.edit(Edit::scene(edit));
            self.open = None;
        }
        if !open {
            self.open = None;
        }
    }
}
