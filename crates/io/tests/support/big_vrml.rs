//! Large generated VRML97 files for the import benchmark: `blocks` animated Transforms, each
//! with a shape whose IndexedFaceSet is a wavy grid of 12 × 12 points (121 quads, crease angle
//! 0.5), a material, and every tenth Transform driven by a 13-key PositionInterpolator and a
//! 5-key OrientationInterpolator from one TimeSensor. About 7.8 kB per block.

use std::fmt::Write;

/// A .wrl of `blocks` blocks.
#[must_use]
pub fn wrl(blocks: usize) -> String {
    let mut s = String::with_capacity(blocks * 7800 + 200);
    s.push_str("#VRML V2.0 utf8\nDEF Clock TimeSensor { cycleInterval 4 loop TRUE }\n");
    for b in 0..blocks {
        let (x, z) = ((b % 100) as f32 * 3.0, (b / 100) as f32 * 3.0);
        let _ = write!(s, "DEF Part{b} Transform {{\n  translation {x} 0 {z}\n  children Shape {{\n");
        let _ = writeln!(
            s,
            "    appearance Appearance {{ material Material {{ diffuseColor {} {} 0.5 }} }}",
            (b % 7) as f32 / 7.0,
            (b % 11) as f32 / 11.0
        );
        s.push_str(
            "    geometry IndexedFaceSet {\n      creaseAngle 0.5\n      coord Coordinate { point [\n",
        );
        for i in 0..12 {
            for j in 0..12 {
                let y = ((i as f32 * 0.7 + b as f32).sin() * (j as f32 * 0.5).cos()) * 0.3;
                let _ = writeln!(s, "        {:.4} {:.4} {:.4},", i as f32 * 0.2, y, j as f32 * 0.2);
            }
        }
        s.push_str("      ] }\n      coordIndex [\n");
        for i in 0..11 {
            for j in 0..11 {
                let a = i * 12 + j;
                let _ = writeln!(s, "        {} {} {} {} -1,", a, a + 1, a + 13, a + 12);
            }
        }
        s.push_str("      ]\n    }\n  }\n}\n");
        if b % 10 == 0 {
            let _ = write!(s, "DEF Path{b} PositionInterpolator {{\n  key [");
            for k in 0..13 {
                let _ = write!(s, " {:.3}", k as f32 / 12.0);
            }
            s.push_str(" ]\n  keyValue [");
            for k in 0..13 {
                let _ = write!(s, " {} {:.3} {}", x, (k as f32 * 0.5).sin(), z);
            }
            let _ = write!(
                s,
                " ]\n}}\nDEF Turn{b} OrientationInterpolator {{ key [ 0 0.25 0.5 0.75 1 ] keyValue [ 0 1 0 0, 0 1 0 1.5, 0 1 0 3, 0 1 0 4.5, 0 1 0 6 ] }}\n"
            );
            let _ = writeln!(s, "ROUTE Clock.fraction_changed TO Path{b}.set_fraction");
            let _ = writeln!(s, "ROUTE Clock.fraction_changed TO Turn{b}.set_fraction");
            let _ = writeln!(s, "ROUTE Path{b}.value_changed TO Part{b}.set_translation");
            let _ = writeln!(s, "ROUTE Turn{b}.value_changed TO Part{b}.set_rotation");
        }
    }
    s
}
