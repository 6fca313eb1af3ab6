//! Error messages that quote untrusted input stay short.

use std::borrow::Cow;

/// Longest token (a run of characters without white space) an error message quotes whole.
pub const MAX_QUOTED_CHARS: usize = 80;

/// `text` with every token longer than [`MAX_QUOTED_CHARS`] characters cut to its first
/// [`MAX_QUOTED_CHARS`] − 1 characters and an ellipsis, followed by its length in bytes, e.g.
/// `` `aaaa…aaaa… (52428802 bytes) ``. Parsers quote the token they stumbled on, and a
/// hostile file's token can be megabytes long. Clipping clipped text changes nothing.
#[must_use]
pub fn clip_long_tokens(text: &str) -> Cow<'_, str> {
    let long = |t: &str| t.chars().nth(MAX_QUOTED_CHARS).is_some();
    if !text.split(char::is_whitespace).any(long) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len().min(4 * MAX_QUOTED_CHARS));
    let mut rest = text;
    while !rest.is_empty() {
        let start = rest.find(|c: char| !c.is_whitespace()).unwrap_or(rest.len());
        out.push_str(&rest[..start]);
        rest = &rest[start..];
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let token = &rest[..end];
        if long(token) {
            let cut = token.char_indices().nth(MAX_QUOTED_CHARS - 1).map_or(token.len(), |(i, _)| i);
            out.push_str(&token[..cut]);
            out.push_str(&format!("… ({} bytes)", token.len()));
        } else {
            out.push_str(token);
        }
        rest = &rest[end..];
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_text_is_unchanged_and_long_tokens_are_clipped() {
        assert_eq!(clip_long_tokens("unexpected `foo` at 3"), "unexpected `foo` at 3");
        let huge = "x".repeat(1_000_000);
        let text = format!("expected a number, found `{huge}` here");
        let clipped = clip_long_tokens(&text);
        assert!(clipped.len() < 200, "{clipped}");
        assert!(clipped.starts_with("expected a number, found `xxx"), "{clipped}");
        assert!(clipped.ends_with("… (1000002 bytes) here"), "{clipped}");
        let wide = "é".repeat(100);
        assert!(clip_long_tokens(&wide).contains("(200 bytes)"));
        assert_eq!(clip_long_tokens(&clipped), clipped, "idempotent");
    }
}
