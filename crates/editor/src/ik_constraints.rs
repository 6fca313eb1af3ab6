//! IK constraints in the editor (issue 19): keeping the chain of IK posing as a constraint whose
//! target is keyed at the current frame ("Keep as IK constraint"), and baking a constraint to
//! rotation keys ("Bake IK to keys"), each one undo step. The inspector shows a selected joint's
//! constraints with their target and blend channels (`panels::inspector`); the evaluator solves
//! them (docs/ik.md, "IK constraints").

use keyrig_core::{Animated, IkConstraint, Key, RawTrack};

use crate::app::EditorApp;

impl EditorApp {
    /// Indices of object `object`'s IK constraints whose end joint is `joint`.
    #[must_use]
    pub fn ik_constraints_ending_at(&self, object: usize, joint: usize) -> Vec<usize> {
        keyrig_edit::ik::ending_at(self.doc.scene(), object, joint)
    }

    /// Adds an IK constraint on the IK posing chain that ends at `joint` (its length as chosen
    /// in the inspector): its target keyed at the current frame where the joint is now (object
    /// space), no pole (the chain bends as its keyed pose does), blend 1. One undo step.
    pub fn keep_ik_constraint(&mut self, object: usize, joint: usize) {
        let chain = match self.ik_chain(object, joint) {
            Ok(chain) => chain,
            Err(e) => {
                self.error(e.to_string());
                return;
            }
        };
        let Some(target) = self.object_pose_now(object).and_then(|p| p.object_from_joint.get(joint).copied())
        else {
            return;
        };
        let target = glam::Vec3::from(target.translation);
        let time = f64::from(self.session.playback.whole_frame()) / self.doc.scene().fps.max(1e-9);
        let Some(skeleton) = self.doc.scene().objects.get(object).and_then(|o| o.skeleton.as_ref()) else {
            return;
        };
        let base = format!("IK {}", chain.names.last().cloned().unwrap_or_default());
        let taken = |name: &str| skeleton.ik_constraints.iter().any(|c| c.name == name);
        let name = (1..)
            .map(|i| if i == 1 { base.clone() } else { format!("{base} {i}") })
            .find(|n| !taken(n))
            .unwrap_or(base);
        let mut constraint = IkConstraint::new(name.clone(), joint, chain.bones(), target);
        constraint.target = Animated::new(target, RawTrack::new(vec![Key::new(time, target)]));
        self.doc.edit("Keep as IK constraint", |scene| {
            if let Some(skeleton) = scene.objects.get_mut(object).and_then(|o| o.skeleton.as_mut()) {
                skeleton.ik_constraints.push(constraint);
            }
        });
        self.info(format!("IK constraint \"{name}\": {} follows its target", chain.describe()));
    }

    /// Bakes IK constraint `constraint` of `object` to rotation keys on its chain at every frame
    /// of the scene's range and sets its blend to 0 ([`keyrig_eval::bake_ik_constraint`]). One
    /// undo step.
    pub fn bake_ik_constraint(&mut self, object: usize, constraint: usize) {
        let range = self.doc.scene().frame_range;
        let mut result = None;
        self.doc.edit("Bake IK to keys", |scene| {
            result = Some(keyrig_eval::bake_ik_constraint(scene, object, constraint, range.start, range.end));
        });
        match result {
            Some(Ok(baked)) => {
                self.info(format!(
                    "Baked IK to keys: {} joint(s), {} frame(s); the constraint's blend is now 0",
                    baked.joints.len(),
                    baked.frames
                ));
            }
            Some(Err(e)) => self.error(format!("Bake IK to keys: {e}")),
            None => {}
        }
    }

    /// Switches child-of constraint `constraint` of `object` to `target` at the current time
    /// without moving the object there ([`keyrig_eval::switch_parent`]: a parent entry with the
    /// offset taken now, a Step key on the parent channel). One undo step; nothing changes when
    /// the switch is refused.
    pub fn switch_parent(&mut self, object: usize, constraint: usize, target: keyrig_core::AimTarget) {
        let time = self.time();
        let mut switched = self.doc.scene().clone();
        match keyrig_eval::switch_parent(&mut switched, object, constraint, time, target.clone()) {
            Ok(_) => {
                let Some(new) =
                    switched.objects.get(object).and_then(|o| o.constraints.get(constraint)).cloned()
                else {
                    return;
                };
                let label = format!("switch {} to {}", new.name, keyrig_edit::edit::target_label(&target));
                self.doc.edit(&label, |scene| {
                    if let Some(c) =
                        scene.objects.get_mut(object).and_then(|o| o.constraints.get_mut(constraint))
                    {
                        *c = new;
                    }
                });
                self.info(format!("{label} at frame {}", self.session.playback.whole_frame()));
            }
            Err(e) => self.error(format!("Switch parent: {e}")),
        }
    }
}
