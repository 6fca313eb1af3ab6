//! Prints what keyrig imports from VRML/X3D/Inventor files: `cargo run -p keyrig-io --example vrml_dump -- FILE…`.
fn main() {
    for arg in std::env::args().skip(1) {
        match keyrig_io::vrml::import_vrml_file(std::path::Path::new(&arg)) {
            Ok(m) => {
                println!(
                    "{arg}: {} ({} objects, {} lights, {} views, {:.3} s)",
                    m.encoding.name(),
                    m.objects.len(),
                    m.lights.len(),
                    m.views.len(),
                    m.duration
                );
                for (o, mesh) in m.objects.iter().zip(&m.meshes) {
                    let anim = [o.translation.is_animated(), o.rotation.is_animated(), o.scale.is_animated()];
                    let joints: Vec<String> = o
                        .skeleton
                        .as_ref()
                        .map(|s| {
                            s.joints
                                .iter()
                                .map(|j| {
                                    format!(
                                        "{}{}",
                                        j.name,
                                        if j.translation.is_animated()
                                            || j.rotation.is_animated()
                                            || j.scale.is_animated()
                                        {
                                            "*"
                                        } else {
                                            ""
                                        }
                                    )
                                })
                                .collect()
                        })
                        .unwrap_or_default();
                    println!("  object {} T{:?} anim {:?} joints {:?} verts {} tris {} colour {:?} tex {} morph {:?}", o.name, o.translation.value, anim, joints, mesh.positions.len(), mesh.indices.len() / 3, mesh.material.base_colour, mesh.material.base_colour_texture.is_some(), mesh.morph.as_ref().map(|m| (m.times.len(), m.period)));
                }
                for l in &m.lights {
                    println!(
                        "  light {} {:?} pos {:?} dir {:?} anim {:?}",
                        l.name,
                        l.kind,
                        l.position.value,
                        l.direction.value,
                        [
                            l.position.is_animated(),
                            l.direction.is_animated(),
                            l.colour.is_animated(),
                            l.intensity.is_animated()
                        ]
                    );
                }
                for v in &m.views {
                    println!("  view {} at {:?}", v.name, v.position);
                }
                for s in m.skipped_lines() {
                    println!("  skipped: {s}");
                }
            }
            Err(e) => println!("{arg}: ERROR {e}"),
        }
    }
}
