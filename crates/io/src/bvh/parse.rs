//! The BVH text reader: HIERARCHY (ROOT, JOINT, End Site, OFFSET, CHANNELS) and MOTION
//! (`Frames:`, `Frame Time:`, one line of values per frame) into a [`BvhFile`].
//!
//! The file is untrusted. The reader is a loop over tokens with an explicit stack of open
//! joints (no recursion, so a 10,000-deep hierarchy cannot overflow the thread's stack), it
//! allocates the frame data only after checking that the bytes left in the file can hold the
//! declared frames, and every error names the line and column.

use glam::Vec3;

use super::{
    BvhChannel, BvhError, BvhErrorKind, BvhFile, BvhJoint, MAX_ABS_VALUE, MAX_FRAME_TIME, MIN_FRAME_TIME,
};
use crate::message::clip_long_tokens;

/// Tokens separated by ASCII white space, with line counting.
struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    /// 1-based line of `pos`.
    line: usize,
    /// Byte offset where that line starts.
    line_start: usize,
}

/// A token: its text and where it starts.
#[derive(Clone, Copy)]
struct Token<'a> {
    text: &'a str,
    at: usize,
    line: usize,
    line_start: usize,
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c)
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str) -> Self {
        // A UTF-8 byte-order mark is not part of the text.
        let pos = if text.starts_with('\u{feff}') { 3 } else { 0 };
        Lexer { text, pos, line: 1, line_start: 0 }
    }

    /// Skips white space, counting lines; with `stop_at_newline`, stops after the first line
    /// break (returns true when one was passed).
    fn skip_space(&mut self, stop_at_newline: bool) -> bool {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() && is_space(bytes[self.pos]) {
            let b = bytes[self.pos];
            self.pos += 1;
            if b == b'\n' {
                self.line += 1;
                self.line_start = self.pos;
                if stop_at_newline {
                    return true;
                }
            }
        }
        false
    }

    fn next(&mut self) -> Option<Token<'a>> {
        self.skip_space(false);
        self.word()
    }

    /// The word at `pos` (no white space skipped), if any.
    fn word(&mut self) -> Option<Token<'a>> {
        let bytes = self.text.as_bytes();
        let start = self.pos;
        while self.pos < bytes.len() && !is_space(bytes[self.pos]) {
            self.pos += 1;
        }
        (self.pos > start).then(|| Token {
            text: &self.text[start..self.pos],
            at: start,
            line: self.line,
            line_start: self.line_start,
        })
    }

    /// The rest of the current line, trimmed (the line break is not consumed).
    fn rest_of_line(&mut self) -> Token<'a> {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() && matches!(bytes[self.pos], b' ' | b'\t') {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < bytes.len() && bytes[self.pos] != b'\n' {
            self.pos += 1;
        }
        let text = self.text[start..self.pos].trim_end();
        Token { text, at: start, line: self.line, line_start: self.line_start }
    }

    /// The place just past the last character read.
    fn here(&self) -> Token<'a> {
        Token { text: "", at: self.pos, line: self.line, line_start: self.line_start }
    }
}

impl Token<'_> {
    fn column(&self, text: &str) -> usize {
        text.get(self.line_start..self.at).map_or(1, |s| s.chars().count() + 1)
    }
}

/// The reader: the text and the file name errors are reported with.
struct Reader<'a> {
    lex: Lexer<'a>,
    file: Option<&'a std::path::Path>,
}

impl<'a> Reader<'a> {
    fn error(&self, at: Token<'_>, kind: BvhErrorKind) -> BvhError {
        BvhError {
            file: self.file.map(std::path::Path::to_path_buf),
            place: Some(super::Place { line: at.line, column: at.column(self.lex.text) }),
            kind,
        }
    }

    fn syntax(&self, at: Token<'_>, message: String) -> BvhError {
        self.error(at, BvhErrorKind::Syntax(clip_long_tokens(&message).into_owned()))
    }

    /// The next token, or an error saying the file ended where `what` was expected.
    fn expect_token(&mut self, what: &str) -> Result<Token<'a>, BvhError> {
        match self.lex.next() {
            Some(t) => Ok(t),
            None => Err(self.error(
                self.lex.here(),
                BvhErrorKind::Truncated(format!("the file ends where {what} was expected")),
            )),
        }
    }

    fn expect_word(&mut self, word: &str) -> Result<Token<'a>, BvhError> {
        let t = self.expect_token(&format!("`{word}`"))?;
        if t.text == word {
            Ok(t)
        } else {
            Err(self.syntax(t, format!("expected `{word}`, found `{}`", t.text)))
        }
    }

    fn number(&mut self, what: &str) -> Result<f32, BvhError> {
        let t = self.expect_token(what)?;
        value(t.text).map_err(|m| self.error(t, m))
    }

    fn offset(&mut self) -> Result<Vec3, BvhError> {
        Ok(Vec3::new(
            self.number("the OFFSET's x")?,
            self.number("the OFFSET's y")?,
            self.number("the OFFSET's z")?,
        ))
    }

    /// The name after ROOT or JOINT: the rest of its line (names may hold spaces), with a `{`
    /// at its end taken as the joint's opening brace. Returns the name and whether the brace
    /// was there.
    fn joint_name(&mut self, keyword: Token<'_>) -> Result<(String, bool), BvhError> {
        let t = self.lex.rest_of_line();
        let (name, brace) = match t.text.strip_suffix('{') {
            Some(n) => (n.trim_end(), true),
            None => (t.text, false),
        };
        if name.is_empty() {
            return Err(self.syntax(keyword, format!("`{}` needs a name on its line", keyword.text)));
        }
        Ok((name.to_owned(), brace))
    }
}

/// Powers of ten exactly representable in f64.
const POW10: [f64; 16] =
    [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15];

/// A plain decimal (`-12.3456`, `.5`, `7`: an optional sign, at most 15 digits, at most one
/// point, no exponent), read as `digits / 10^decimals` in f64 (both exact, so the quotient is
/// the correctly rounded f64) and then rounded to f32. `None` for anything else, which
/// [`value`] hands to the standard parser. Motion capture files are almost all such numbers,
/// and this is several times faster than `str::parse::<f32>`; the two agree exactly except
/// where the f64 lands on an f32 rounding tie (one unit in the last place at most; never for a
/// number written as the shortest form of an f32, which is what exporters write).
fn plain_decimal(text: &str) -> Option<f32> {
    let bytes = text.as_bytes();
    let (negative, digits) = match bytes.first()? {
        b'-' => (true, &bytes[1..]),
        b'+' => (false, &bytes[1..]),
        _ => (false, bytes),
    };
    if digits.is_empty() || digits.len() > 16 {
        return None;
    }
    let mut mantissa: u64 = 0;
    let mut count = 0usize;
    let mut decimals: Option<usize> = None;
    for &c in digits {
        match c {
            b'0'..=b'9' => {
                mantissa = mantissa * 10 + u64::from(c - b'0');
                count += 1;
                if let Some(d) = decimals.as_mut() {
                    *d += 1;
                }
            }
            b'.' if decimals.is_none() => decimals = Some(0),
            _ => return None,
        }
    }
    if count == 0 || count > 15 {
        return None;
    }
    let v = (mantissa as f64 / POW10[decimals.unwrap_or(0)]) as f32;
    Some(if negative { -v } else { v })
}

/// A value of the file: a finite number within ±[`MAX_ABS_VALUE`].
fn value(text: &str) -> Result<f32, BvhErrorKind> {
    if let Some(v) = plain_decimal(text).filter(|v| v.abs() <= MAX_ABS_VALUE) {
        return Ok(v);
    }
    let v: f32 = text.parse().map_err(|_| {
        BvhErrorKind::Syntax(clip_long_tokens(&format!("expected a number, found `{text}`")).into_owned())
    })?;
    if !v.is_finite() || v.abs() > MAX_ABS_VALUE {
        return Err(BvhErrorKind::Value(
            clip_long_tokens(&format!(
                "`{text}` is not a usable value: values must be finite and within ±{MAX_ABS_VALUE}"
            ))
            .into_owned(),
        ));
    }
    Ok(v)
}

/// Reads a whole BVH text. `file` names the file in errors.
pub(super) fn parse(text: &str, file: Option<&std::path::Path>) -> Result<BvhFile, BvhError> {
    let mut r = Reader { lex: Lexer::new(text), file };
    let first = match r.lex.next() {
        Some(t) => t,
        None => {
            return Err(r.error(
                r.lex.here(),
                BvhErrorKind::Truncated("the file is empty (a BVH file starts with `HIERARCHY`)".to_owned()),
            ))
        }
    };
    if first.text != "HIERARCHY" {
        return Err(r.syntax(first, format!("a BVH file starts with `HIERARCHY`, not `{}`", first.text)));
    }
    let root = r.expect_word("ROOT")?;
    let joints = hierarchy(&mut r, root)?;
    let channel_count = joints.iter().map(|j| j.channels.len()).sum::<usize>();

    let motion = r.expect_token("`MOTION`")?;
    if motion.text == "ROOT" {
        return Err(r.error(
            motion,
            BvhErrorKind::Unsupported(
                "a second ROOT: keyrig reads one skeleton (one ROOT) per BVH file".to_owned(),
            ),
        ));
    }
    if motion.text != "MOTION" {
        return Err(
            r.syntax(motion, format!("expected `MOTION` after the hierarchy, found `{}`", motion.text))
        );
    }
    // `Frames:` (or `Frames :`) and a whole number.
    let frames_word = r.expect_token("`Frames:`")?;
    let count_token = match frames_word.text {
        "Frames:" => r.expect_token("the frame count")?,
        "Frames" => {
            r.expect_word(":")?;
            r.expect_token("the frame count")?
        }
        other => return Err(r.syntax(frames_word, format!("expected `Frames:`, found `{other}`"))),
    };
    let frames: u64 = count_token.text.parse().map_err(|_| {
        r.syntax(
            count_token,
            format!("expected the frame count (a whole number ≥ 0), found `{}`", count_token.text),
        )
    })?;
    if frames > i32::MAX as u64 {
        return Err(r.error(
            count_token,
            BvhErrorKind::Limit(format!("{frames} frames: keyrig's frame numbers go up to {}", i32::MAX)),
        ));
    }
    r.expect_word("Frame")?;
    let time_word = r.expect_token("`Time:`")?;
    let time_token = match time_word.text {
        "Time:" => r.expect_token("the frame time")?,
        "Time" => {
            r.expect_word(":")?;
            r.expect_token("the frame time")?
        }
        other => return Err(r.syntax(time_word, format!("expected `Frame Time:`, found `Frame {other}`"))),
    };
    let frame_time: f64 = time_token.text.parse().map_err(|_| {
        r.syntax(time_token, format!("expected the frame time in seconds, found `{}`", time_token.text))
    })?;
    // A hair of slack at both ends, so that `1 / fps` written back by the exporter reads again.
    let allowed = MIN_FRAME_TIME * (1.0 - 1e-9)..=MAX_FRAME_TIME * (1.0 + 1e-9);
    if !(frame_time.is_finite() && allowed.contains(&frame_time)) {
        return Err(r.error(
            time_token,
            BvhErrorKind::Value(
                clip_long_tokens(&format!(
                    "frame time `{}` must be between {MIN_FRAME_TIME} and {MAX_FRAME_TIME} seconds",
                    time_token.text
                ))
                .into_owned(),
            ),
        ));
    }
    let fps = super::fps_of_frame_time(frame_time, time_token.text);
    // Nothing more on the `Frame Time:` line.
    r.lex.skip_space_on_line();
    if let Some(extra) = r.lex.word() {
        return Err(r.syntax(extra, format!("unexpected `{}` after the frame time", extra.text)));
    }
    let frames = frames as usize;
    let values = frame_values(&mut r, frames, channel_count, count_token)?;
    Ok(BvhFile { joints, frames, frame_time, fps, channel_count, values })
}

impl Lexer<'_> {
    /// Skips spaces and tabs (not line breaks).
    fn skip_space_on_line(&mut self) {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() && matches!(bytes[self.pos], b' ' | b'\t' | b'\r' | 0x0b | 0x0c) {
            self.pos += 1;
        }
    }
}

/// The joint tree after `ROOT`, parents first, with End Sites as joints of their own.
fn hierarchy(r: &mut Reader<'_>, root: Token<'_>) -> Result<Vec<BvhJoint>, BvhError> {
    let mut joints: Vec<BvhJoint> = Vec::new();
    // The open joints, innermost last; each with whether its OFFSET was read.
    let mut stack: Vec<usize> = Vec::new();
    let mut has_offset: Vec<bool> = Vec::new();
    let mut next_channel = 0usize;

    let open = |r: &mut Reader<'_>, brace: bool| -> Result<(), BvhError> {
        if !brace {
            r.expect_word("{")?;
        }
        Ok(())
    };

    let (name, brace) = r.joint_name(root)?;
    open(r, brace)?;
    joints.push(BvhJoint::new(name, None, false, root.line));
    has_offset.push(false);
    stack.push(0);

    while let Some(&current) = stack.last() {
        let t = r.expect_token("`}` closing the joint")?;
        let end_site = joints[current].end_site;
        match t.text {
            "OFFSET" => {
                if has_offset[current] {
                    return Err(r.syntax(t, "a second OFFSET in one joint".to_owned()));
                }
                joints[current].offset = r.offset()?;
                has_offset[current] = true;
            }
            "CHANNELS" if !end_site => {
                if joints[current].channels_read {
                    return Err(r.syntax(t, "a second CHANNELS in one joint".to_owned()));
                }
                let count_token = r.expect_token("the channel count")?;
                let count: usize = match count_token.text.parse() {
                    Ok(n) if n <= 6 => n,
                    _ => {
                        return Err(r.syntax(
                            count_token,
                            format!("a joint has 0 to 6 channels, not `{}`", count_token.text),
                        ))
                    }
                };
                let mut channels = Vec::with_capacity(count);
                for _ in 0..count {
                    let c = r.expect_token("a channel name")?;
                    let channel = BvhChannel::from_name(c.text).ok_or_else(|| {
                        r.syntax(
                            c,
                            format!(
                                "expected a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation), found `{}`: CHANNELS {count} names {count}",
                                c.text
                            ),
                        )
                    })?;
                    if channels.contains(&channel) {
                        return Err(r.syntax(c, format!("channel {} is listed twice", channel.name())));
                    }
                    channels.push(channel);
                }
                let joint = &mut joints[current];
                joint.channels = channels;
                joint.first_channel = next_channel;
                joint.channels_read = true;
                next_channel += count;
            }
            "JOINT" if !end_site => {
                let (name, brace) = r.joint_name(t)?;
                open(r, brace)?;
                joints.push(BvhJoint::new(name, Some(current), false, t.line));
                has_offset.push(false);
                stack.push(joints.len() - 1);
            }
            "End" if !end_site => {
                r.expect_word("Site")?;
                r.expect_word("{")?;
                joints.push(BvhJoint::new(String::new(), Some(current), true, t.line));
                has_offset.push(false);
                stack.push(joints.len() - 1);
            }
            "}" => {
                if !has_offset[current] {
                    let what = if end_site {
                        "this End Site".to_owned()
                    } else {
                        format!("joint `{}`", joints[current].name)
                    };
                    return Err(r.syntax(t, format!("{what} has no OFFSET")));
                }
                stack.pop();
            }
            other => {
                let expected = if end_site {
                    "`OFFSET` or `}` in an End Site"
                } else {
                    "`OFFSET`, `CHANNELS`, `JOINT`, `End Site` or `}`"
                };
                return Err(r.syntax(t, format!("expected {expected}, found `{other}`")));
            }
        }
    }
    Ok(joints)
}

/// The MOTION values: `frames` lines of `channels` numbers each (blank lines between them are
/// allowed), then nothing but white space. The declared count is checked against the bytes
/// left before anything is allocated for it.
fn frame_values(
    r: &mut Reader<'_>,
    frames: usize,
    channels: usize,
    count_token: Token<'_>,
) -> Result<Vec<f32>, BvhError> {
    let text = r.lex.text;
    if channels > 0 {
        // Each value takes at least one character and one separator (the last may end the file).
        let left = text.len() - r.lex.pos;
        let fit = (left + 1) / (2 * channels);
        if frames > fit {
            return Err(r.error(
                count_token,
                BvhErrorKind::Truncated(format!(
                    "`Frames: {frames}` declares {frames} frames of {channels} values, but the {left} bytes after it hold at most {fit}"
                )),
            ));
        }
    }
    let mut values = Vec::with_capacity(frames * channels);
    if channels > 0 {
        for frame in 0..frames {
            r.lex.skip_space(false);
            let line_start = r.lex.here();
            let mut on_line = 0usize;
            loop {
                r.lex.skip_space_on_line();
                let Some(t) = r.lex.word() else { break };
                if on_line == channels {
                    return Err(r.syntax(
                        t,
                        format!(
                            "frame {frame} has more than {channels} values (`{}` is one too many): the hierarchy's CHANNELS add up to {channels}",
                            t.text
                        ),
                    ));
                }
                values.push(value(t.text).map_err(|k| r.error(t, k))?);
                on_line += 1;
            }
            if on_line < channels {
                if r.lex.pos >= text.len() {
                    return Err(r.error(
                        r.lex.here(),
                        BvhErrorKind::Truncated(format!(
                            "the file ends in frame {frame} of {frames}, after {on_line} of its {channels} values"
                        )),
                    ));
                }
                return Err(r.syntax(
                    line_start,
                    format!(
                        "frame {frame} has {on_line} values, but the hierarchy's CHANNELS add up to {channels}"
                    ),
                ));
            }
        }
    }
    if let Some(extra) = r.lex.next() {
        return Err(r.syntax(
            extra,
            format!("`{}` after the last of the {frames} frames that `Frames:` declares", extra.text),
        ));
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_decimals_read_as_the_standard_parser_reads_them() {
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            state >> 11
        };
        let mut off_by_one_ulp = 0;
        for i in 0..200_000 {
            let digits = 1 + (next() % 15) as usize;
            let mantissa = next() % 10u64.pow(digits as u32);
            let point = (next() % (digits as u64 + 1)) as usize;
            let mut text = format!("{mantissa:0digits$}");
            text.insert(point, '.');
            if i % 2 == 0 {
                text.insert(0, '-');
            }
            let fast = plain_decimal(&text).expect("plain");
            let slow: f32 = text.parse().expect("number");
            if fast != slow {
                assert_eq!((fast.to_bits() as i64 - slow.to_bits() as i64).abs(), 1, "{text}");
                off_by_one_ulp += 1;
            }
        }
        assert!(off_by_one_ulp < 20, "{off_by_one_ulp}");
        // Shortest forms of f32 values come back exactly.
        for _ in 0..200_000 {
            let v = f32::from_bits((next() as u32) & 0x4fff_ffff);
            let text = format!("{v}");
            if let Some(fast) = plain_decimal(&text) {
                assert_eq!(fast, v, "{text}");
            }
        }
        for other in ["", "-", ".", "1e5", "1.2.3", "0x1", "inf", "NaN", "1234567890123456", "--1", "+", "1-"]
        {
            assert_eq!(plain_decimal(other), None, "{other}");
        }
        assert_eq!(plain_decimal("-0"), Some(-0.0));
        assert_eq!(plain_decimal(".0083333"), Some(0.0083333));
        assert_eq!(plain_decimal("+5."), Some(5.0));
    }
}
