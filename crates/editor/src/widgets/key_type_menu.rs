//! The *Key type* entries of the dope sheet's and the curve editor's context menus: the type
//! of every selected key ([`KeyType`]: keyframe, breakdown, moving hold, extreme) in one undo
//! step. Locked channels keep theirs.

use egui::Ui;
use keyrig_core::KeyType;

use crate::actions::{Action, Actions, Edit};
use crate::session::{KeyRef, Selection};
use keyrig_edit::SceneEdit;

/// One button per key type; a click sets it on every selected key (one undo step) and closes
/// the menu. Disabled while no key is selected.
pub fn key_type_menu_ui(ui: &mut Ui, selection: &Selection, actions: &mut Actions) {
    let keys: Vec<KeyRef> = selection.keys.iter().copied().collect();
    ui.label(egui::RichText::new("Key type").small().weak());
    for key_type in KeyType::ALL {
        let button = ui.add_enabled(!keys.is_empty(), egui::Button::new(key_type.label()));
        if button.clicked() {
            actions.push(Action::CloseGroup);
            actions.edit(Edit::scene(SceneEdit::KeyType { keys: keys.clone(), key_type }));
            ui.close();
        }
    }
}
