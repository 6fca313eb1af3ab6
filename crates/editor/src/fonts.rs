//! The editor's fonts: egui's defaults (Ubuntu Light, Hack, Noto Emoji, emoji-icon-font) with a
//! symbol font as the last fallback of both families, so that every glyph the UI draws — the
//! record and key markers ● ⏺ ◆, the transport symbols, arrows, degrees, × and − — has an
//! outline instead of an empty box.
//!
//! The fallback is a subset of DejaVu Sans (Bitstream Vera licence with DejaVu's public-domain
//! changes; `assets/fonts/LICENSE-DejaVu.txt`): Latin-1, General Punctuation, arrows,
//! mathematical operators, Miscellaneous Technical and Geometric Shapes, which is where the
//! UI's symbols are (`assets/fonts/README.md` says how it was made). The test below fails when
//! a string in the editor's sources uses a character no configured font has.

use egui::{FontData, FontDefinitions, FontFamily};

/// Name of the symbol fallback in [`FontDefinitions::font_data`].
pub const SYMBOL_FONT: &str = "keyrig-symbols (DejaVu Sans subset)";

/// The symbol font's bytes (TrueType).
const SYMBOL_FONT_BYTES: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans-symbols.ttf");

/// egui's default fonts plus the symbol fallback at the end of every family.
#[must_use]
pub fn definitions() -> FontDefinitions {
    let mut fonts = FontDefinitions::default();
    fonts
        .font_data
        .insert(SYMBOL_FONT.to_owned(), std::sync::Arc::new(FontData::from_static(SYMBOL_FONT_BYTES)));
    for family in [FontFamily::Proportional, FontFamily::Monospace] {
        fonts.families.entry(family).or_default().push(SYMBOL_FONT.to_owned());
    }
    fonts
}

/// Installs [`definitions`] in `ctx` (they take effect from the next pass).
pub fn install(ctx: &egui::Context) {
    ctx.set_fonts(definitions());
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;
    use std::path::Path;

    use super::*;

    /// Every non-ASCII character inside a string or char literal of the editor's UI sources
    /// (comment lines skipped; the command-line tool's sources, which print to a terminal, are
    /// left out).
    fn ui_characters() -> BTreeSet<char> {
        fn visit(dir: &Path, out: &mut BTreeSet<char>) {
            for entry in std::fs::read_dir(dir).expect("editor sources") {
                let path = entry.expect("entry").path();
                if path.is_dir() {
                    if path.file_name().is_some_and(|n| n != "cli") {
                        visit(&path, out);
                    }
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path).expect("a source file");
                    // Between unescaped double quotes (strings may continue over lines), or a
                    // char literal such as '●'.
                    let mut in_string = false;
                    for line in text.lines() {
                        if !in_string && line.trim_start().starts_with("//") {
                            continue;
                        }
                        let chars: Vec<char> = line.chars().collect();
                        for (i, &c) in chars.iter().enumerate() {
                            let before = i.checked_sub(1).map(|j| chars[j]);
                            let after = chars.get(i + 1).copied();
                            let char_literal = before == Some('\'') && after == Some('\'');
                            if c == '"' && before != Some('\\') && !char_literal {
                                in_string = !in_string;
                            } else if (in_string || char_literal) && !c.is_ascii() {
                                out.insert(c);
                            }
                        }
                    }
                }
            }
        }
        let mut out = BTreeSet::new();
        visit(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut out);
        out
    }

    /// The characters that no font of `family` draws once `fonts` are installed.
    fn missing(fonts: FontDefinitions, family: &FontFamily, chars: &BTreeSet<char>) -> Vec<char> {
        let ctx = egui::Context::default();
        ctx.set_fonts(fonts);
        // Fonts are (re)built at the start of a pass.
        let _ = ctx.run_ui(egui::RawInput::default(), |_| {});
        let font = egui::FontId::new(14.0, family.clone());
        ctx.fonts_mut(|f| chars.iter().copied().filter(|&c| !f.has_glyph(&font, c)).collect())
    }

    #[test]
    fn the_sources_use_the_markers_this_test_is_about() {
        let chars = ui_characters();
        for c in ['●', '◆', '⏺', '▶', '×', '°'] {
            assert!(chars.contains(&c), "{c} is no longer found in the UI strings: {chars:?}");
        }
    }

    #[test]
    fn every_character_of_the_ui_strings_has_a_glyph() {
        let chars = ui_characters();
        for family in [FontFamily::Proportional, FontFamily::Monospace] {
            let missing = missing(definitions(), &family, &chars);
            assert!(
                missing.is_empty(),
                "{family:?}: no configured font draws {missing:?}; add them to the symbol font \
                 (assets/fonts/README.md) or use another character"
            );
        }
    }

    #[test]
    fn the_default_fonts_alone_lack_some_of_them() {
        // Why the symbol font is there: egui's own fonts show these as empty boxes.
        let missing = missing(FontDefinitions::default(), &FontFamily::Proportional, &ui_characters());
        assert!(missing.contains(&'●') || missing.contains(&'◆'), "{missing:?}");
    }
}
