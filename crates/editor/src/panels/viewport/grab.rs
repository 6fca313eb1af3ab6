//! The viewport's grab, as Blender's G after Shift+D: the selection follows the pointer in the
//! plane through it that faces the camera, with no button held, until a click or Enter places
//! it; Escape or a right-click puts it back where it was (a duplicate stays, on the original).
//! Its edits join the undo step that started it ([`GRAB_GROUP`]: Shift+D's duplicate and its
//! move are one step), which the window keeps open while the grab lasts
//! ([`super::Viewport::holds_undo_group`]). A grab places what Shift+D copied: an item whose
//! translation is keyed moves with its whole motion (every translation key moves by the offset,
//! [`Edit::PlaceKeys`], in record mode or not), so the copy plays the original's motion where it
//! was put instead of snapping back at the next frame; an unkeyed item's move is the gizmo's
//! ([`Edit::Pose`]: its value, or a key in record mode).

use egui::{Key, Modifiers, Pos2, Rect};
use glam::Vec3;

use crate::actions::{Action, Actions, Edit};
use crate::camera::{OrbitCamera, Projection};
use crate::context::FrameCtx;
use keyrig_edit::channels::{self, ChannelValue};

use super::targets::{self, Target};

/// The undo group of a grab and the edit that started it.
pub const GRAB_GROUP: &str = "grab";

/// A grab of the viewport.
#[derive(Default)]
pub(super) enum Grab {
    #[default]
    None,
    /// Asked for (Shift+D): starts in the next viewport frame from the selection then.
    Requested,
    /// The selection follows the pointer.
    Moving(Box<Moving>),
    /// Placed or put back by a press: the press's release is swallowed (it neither selects
    /// nor orbits).
    Releasing,
}

pub(super) struct Moving {
    /// The items moved, as they stood when the grab started.
    targets: Vec<Target>,
    /// For each target, its keyed translation when the grab started (`None`: unkeyed).
    keys: Vec<Option<Keyed>>,
    /// The plane they move in (through the pivot, facing the camera).
    plane_point: Vec3,
    plane_normal: Vec3,
    /// The pointer's first point on that plane (none until the pointer is seen).
    start: Option<Vec3>,
    /// The last pointer position a move was pushed for.
    last: Option<Pos2>,
}

impl Grab {
    /// Whether the grab holds the undo group open and owns the pointer.
    pub(super) fn active(&self) -> bool {
        !matches!(self, Grab::None)
    }

    /// One frame of the grab. Returns whether it owns the primary button (and the keyboard's
    /// Enter and Escape) this frame.
    pub(super) fn ui(
        &mut self,
        ui: &egui::Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        projection: &Projection,
        rect: Rect,
    ) -> bool {
        match std::mem::take(self) {
            Grab::None => false,
            Grab::Requested => {
                let items = targets::targets(ctx);
                if items.iter().all(|t| t.translation.is_none() || t.carried) {
                    actions.push(Action::CloseGroup);
                    return false;
                }
                let camera = &ctx.view.camera;
                let plane_normal = (camera.target - camera.eye()).normalize_or(Vec3::NEG_Z);
                let plane_point = targets::pivot_point(&items, targets::Pivot::MedianPoint);
                let keys = items.iter().map(|t| t.translation.and_then(|(id, ..)| keyed(ctx, id))).collect();
                *self = Grab::Moving(Box::new(Moving {
                    targets: items,
                    keys,
                    plane_point,
                    plane_normal,
                    start: None,
                    last: None,
                }));
                self.ui(ui, ctx, actions, projection, rect)
            }
            Grab::Releasing => {
                if ui.input(|i| i.pointer.any_down() || i.pointer.any_released()) {
                    *self = Grab::Releasing;
                }
                true
            }
            Grab::Moving(mut moving) => {
                let (hover, primary, secondary) = ui.input(|i| {
                    (
                        i.pointer.latest_pos(),
                        i.pointer.button_pressed(egui::PointerButton::Primary),
                        i.pointer.button_pressed(egui::PointerButton::Secondary),
                    )
                });
                let (enter, escape) = ui.input_mut(|i| {
                    (i.consume_key(Modifiers::NONE, Key::Enter), i.consume_key(Modifiers::NONE, Key::Escape))
                });
                if escape || secondary {
                    moving.push(actions, Vec3::ZERO);
                    actions.push(Action::CloseGroup);
                    actions.push(Action::Info("Move cancelled".into()));
                    *self = if secondary { Grab::Releasing } else { Grab::None };
                    return true;
                }
                if let Some(at) = hover.filter(|&p| moving.last != Some(p)) {
                    if let Some(on_plane) = projection.on_plane(at, moving.plane_point, moving.plane_normal) {
                        let start = *moving.start.get_or_insert(on_plane);
                        moving.push(actions, on_plane - start);
                        moving.last = Some(at);
                    }
                }
                if enter || primary {
                    actions.push(Action::CloseGroup);
                    actions.push(Action::Info("Moved".into()));
                    *self = if primary { Grab::Releasing } else { Grab::None };
                    return true;
                }
                // Pointer moves and key presses repaint on their own: an idle grab asks for nothing.
                *self = Grab::Moving(moving);
                // The pointer outside the viewport (over the panels) is the panels' again.
                hover.is_some_and(|p| rect.contains(p))
            }
        }
    }
}

impl Moving {
    /// Sets every moved item's translation to where it stood plus the world `offset`.
    fn push(&self, actions: &mut Actions, offset: Vec3) {
        for (t, keyed) in self.targets.iter().zip(&self.keys).filter(|(t, _)| !t.carried) {
            if let Some((id, value, world_to_value)) = t.translation {
                let offset = world_to_value.mul_vec3(offset);
                if let Some(keyed) = keyed {
                    actions.edit(Edit::PlaceKeys {
                        id,
                        keys: keyed.keys.iter().map(|&(time, v)| (time, v + offset)).collect(),
                        rest: keyed.rest + offset,
                        group: GRAB_GROUP.to_owned(),
                    });
                    continue;
                }
                let value = value + offset;
                actions.edit(Edit::Pose {
                    id,
                    value: ChannelValue::Vec3(value),
                    group: GRAB_GROUP.to_owned(),
                });
            }
        }
    }
}

/// A keyed translation as a grab found it: its keys (time, value) and its static value (what a
/// muted channel plays), both moved by the placement.
struct Keyed {
    keys: Vec<(f64, Vec3)>,
    rest: Vec3,
}

/// Channel `id`'s keys and static value when it is a keyed Vec3 channel.
fn keyed(ctx: &FrameCtx<'_>, id: keyrig_edit::channels::ChannelId) -> Option<Keyed> {
    let Some(channels::ChannelRef::Vec3(a)) = channels::channel(ctx.scene(), id) else { return None };
    (!a.track.keys.is_empty())
        .then(|| Keyed { keys: a.track.keys.iter().map(|k| (k.time, k.value)).collect(), rest: a.value })
}
