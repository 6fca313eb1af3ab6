//! Objects hidden from the viewport with H (Alt+H shows them again), as Blender's Hide in the
//! viewport: a view of the session, not a keyed channel (the `visible` attribute is that) and
//! not saved or undone; renders, exports and playblasts draw every object. A hidden object is
//! not drawn, nor its skeleton, nor picked by a click in the viewport; the outliner still
//! lists and selects it. Objects are remembered by name, so deleting or adding others, undo
//! and redo keep what is hidden.

use std::borrow::Cow;
use std::collections::BTreeSet;

use keyrig_core::Scene;
use keyrig_eval::SceneState;

/// The names of the objects hidden in the viewport.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Hidden {
    names: BTreeSet<String>,
}

impl Hidden {
    /// Whether object `o` of `scene` is hidden.
    #[must_use]
    pub fn object(&self, scene: &Scene, o: usize) -> bool {
        !self.names.is_empty() && scene.objects.get(o).is_some_and(|object| self.names.contains(&object.name))
    }

    /// Whether nothing is hidden.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Hides the object named `name`; false when it was hidden already.
    pub fn hide(&mut self, name: &str) -> bool {
        self.names.insert(name.to_owned())
    }

    /// Shows every hidden object of `scene` again; returns how many there were.
    pub fn show_all(&mut self, scene: &Scene) -> usize {
        let shown = scene.objects.iter().filter(|o| self.names.contains(&o.name)).count();
        self.names.clear();
        shown
    }

    /// Follows a renamed object.
    pub fn rename(&mut self, from: &str, to: &str) {
        if self.names.remove(from) {
            self.names.insert(to.to_owned());
        }
    }

    /// The scene state as the viewport draws it: hidden objects invisible and without a
    /// palette (so neither their mesh nor their skeleton is drawn); the state itself, not a
    /// copy, while nothing is hidden.
    #[must_use]
    pub fn drawn<'a>(&self, scene: &Scene, state: &'a SceneState) -> Cow<'a, SceneState> {
        if !(0..state.objects.len()).any(|o| self.object(scene, o)) {
            return Cow::Borrowed(state);
        }
        let mut drawn = state.clone();
        for (o, object) in drawn.objects.iter_mut().enumerate() {
            if self.object(scene, o) {
                object.look.visible = false;
                object.palette = None;
            }
        }
        Cow::Owned(drawn)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::Object;

    #[test]
    fn hidden_objects_are_found_by_name_through_deletes_and_renames() {
        let mut scene = Scene::default();
        for name in ["a", "b", "c"] {
            scene.objects.push(Object::new(name));
        }
        let mut hidden = Hidden::default();
        assert!(hidden.hide("b") && !hidden.hide("b"));
        assert!(!hidden.object(&scene, 0) && hidden.object(&scene, 1) && !hidden.object(&scene, 2));
        scene.objects.remove(0);
        assert!(hidden.object(&scene, 0), "b is still hidden at its new index");
        hidden.rename("b", "bee");
        scene.objects[0].name = "bee".into();
        assert!(hidden.object(&scene, 0));
        assert_eq!(hidden.show_all(&scene), 1);
        assert!(hidden.is_empty() && !hidden.object(&scene, 0));
    }
}
