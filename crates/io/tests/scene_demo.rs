//! `assets/demo.ron` is exactly the serialized `demo_scene()`.
//!
//! After changing `keyrig_io::demo`, regenerate the file with
//! `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_demo`.

use std::path::Path;

use keyrig_io::demo::{demo_scene, DEMO_RON};
use keyrig_io::scene_file;

#[test]
fn committed_demo_file_equals_generated_scene() {
    let generated = scene_file::to_string(&demo_scene()).expect("serialize demo");
    if std::env::var_os("KEYRIG_REGENERATE_DEMO").is_some() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
        std::fs::write(&path, &generated).expect("write assets/demo.ron");
        return;
    }
    assert!(
        DEMO_RON == generated,
        "assets/demo.ron differs from keyrig_io::demo::demo_scene(); regenerate it with \
         KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_demo"
    );
}

#[test]
fn committed_demo_file_loads_to_the_generated_scene() {
    let scene = scene_file::from_str(DEMO_RON, Path::new("assets/demo.ron")).expect("demo.ron loads");
    assert_eq!(scene, demo_scene());
}
