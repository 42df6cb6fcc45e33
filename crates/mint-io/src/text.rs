//! Small helpers for the text formats: a whitespace tokenizer over a byte
//! slice ([`Tokens`]), a line splitter ([`Lines`]), number parsing that never
//! allocates, and [`line_of`], which turns a byte offset into a line number
//! when (and only when) an error is reported.

/// ASCII whitespace as PLY, OBJ, OFF and STL use it.
#[inline]
pub(crate) fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c)
}

/// Whitespace-separated tokens of `data`, starting at `pos`.
#[derive(Debug, Clone)]
pub(crate) struct Tokens<'a> {
    pub(crate) data: &'a [u8],
    pub(crate) pos: usize,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(data: &'a [u8], pos: usize) -> Tokens<'a> {
        Tokens { data, pos }
    }

    /// Skips whitespace and returns the start offset of the next token and
    /// the token; `None` at the end of the data.
    #[inline]
    pub(crate) fn next_tok(&mut self) -> Option<(usize, &'a [u8])> {
        let d = self.data;
        let mut i = self.pos;
        while i < d.len() && is_space(d[i]) {
            i += 1;
        }
        if i >= d.len() {
            self.pos = i;
            return None;
        }
        let start = i;
        while i < d.len() && !is_space(d[i]) {
            i += 1;
        }
        self.pos = i;
        Some((start, &d[start..i]))
    }

    /// Offset of the next non-whitespace byte (or the end).
    pub(crate) fn skip_space(&mut self) -> usize {
        while self.pos < self.data.len() && is_space(self.data[self.pos]) {
            self.pos += 1;
        }
        self.pos
    }
}

/// Lines of `data` from `pos`; each without its `\n` and trailing `\r`.
#[derive(Debug, Clone)]
pub(crate) struct Lines<'a> {
    pub(crate) data: &'a [u8],
    pub(crate) pos: usize,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(data: &'a [u8], pos: usize) -> Lines<'a> {
        Lines { data, pos }
    }

    /// The next line as (start offset, bytes), or `None` at the end.
    #[inline]
    pub(crate) fn next_line(&mut self) -> Option<(usize, &'a [u8])> {
        let d = self.data;
        if self.pos >= d.len() {
            return None;
        }
        let start = self.pos;
        let end = match memchr::memchr(b'\n', &d[start..]) {
            Some(n) => start + n,
            None => d.len(),
        };
        self.pos = end + 1;
        let mut line = &d[start..end];
        if let [rest @ .., b'\r'] = line {
            line = rest;
        }
        Some((start, line))
    }
}

impl<'a> Lines<'a> {
    /// The next logical line: like [`Lines::next_line`], but a line whose
    /// last non-blank character is a backslash continues on the next one
    /// (OBJ's line continuation); the pieces are joined with a space. Only
    /// a continued line is copied.
    pub(crate) fn next_joined(&mut self) -> Option<(usize, std::borrow::Cow<'a, [u8]>)> {
        let (at, first) = self.next_line()?;
        let continued = |l: &[u8]| {
            let t = l.iter().rposition(|&b| b != b' ' && b != b'\t');
            t.filter(|&i| l[i] == b'\\')
        };
        let Some(cut) = continued(first) else { return Some((at, std::borrow::Cow::Borrowed(first))) };
        let mut joined = first[..cut].to_vec();
        while let Some((_, next)) = self.next_line() {
            joined.push(b' ');
            match continued(next) {
                Some(c) => joined.extend_from_slice(&next[..c]),
                None => {
                    joined.extend_from_slice(next);
                    break;
                }
            }
        }
        Some((at, std::borrow::Cow::Owned(joined)))
    }
}

/// Splits a line into whitespace-separated tokens.
#[inline]
pub(crate) fn words(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|&b| is_space(b)).filter(|w| !w.is_empty())
}

/// Parses a decimal floating-point token (also `inf`, `nan`, exponents).
#[inline]
pub(crate) fn parse_f64(tok: &[u8]) -> Option<f64> {
    // Fast path: plain integers are common in hand-written files.
    if let Some(i) = parse_i64(tok) {
        if i == 0 && tok[0] == b'-' {
            return Some(-0.0);
        }
        if i.unsigned_abs() < (1u64 << 53) {
            return Some(i as f64);
        }
    }
    std::str::from_utf8(tok).ok()?.parse::<f64>().ok()
}

/// Parses an optionally signed decimal integer; also accepts a float token
/// with an integral value such as `3.0` (some exporters write those).
#[inline]
pub(crate) fn parse_int(tok: &[u8]) -> Option<i64> {
    if let Some(v) = parse_i64(tok) {
        return Some(v);
    }
    let f = std::str::from_utf8(tok).ok()?.parse::<f64>().ok()?;
    if f.fract() == 0.0 && f.abs() < 9.0e15 {
        Some(f as i64)
    } else {
        None
    }
}

/// Parses an optionally signed decimal integer of at most 18 digits.
#[inline]
pub(crate) fn parse_i64(tok: &[u8]) -> Option<i64> {
    let (neg, digits) = match tok.first()? {
        b'-' => (true, &tok[1..]),
        b'+' => (false, &tok[1..]),
        _ => (false, tok),
    };
    if digits.is_empty() || digits.len() > 18 {
        return None;
    }
    let mut v: i64 = 0;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v * 10 + d as i64;
    }
    Some(if neg { -v } else { v })
}

/// The 1-based line number of byte `offset` in `data`.
pub(crate) fn line_of(data: &[u8], offset: usize) -> u64 {
    let end = offset.min(data.len());
    1 + data[..end].iter().filter(|&&b| b == b'\n').count() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_and_numbers() {
        let mut t = Tokens::new(b"  3 -1.5e2\r\n\tnan x", 0);
        assert_eq!(t.next_tok(), Some((2, &b"3"[..])));
        let (_, tok) = t.next_tok().unwrap();
        assert_eq!(parse_f64(tok), Some(-150.0));
        assert!(parse_f64(t.next_tok().unwrap().1).unwrap().is_nan());
        assert_eq!(parse_f64(t.next_tok().unwrap().1), None);
        assert_eq!(t.next_tok(), None);
        assert_eq!(parse_f64(b"-0").map(f64::to_bits), Some((-0.0f64).to_bits()));
        assert_eq!(parse_int(b"-12"), Some(-12));
        assert_eq!(parse_int(b"4.0"), Some(4));
        assert_eq!(parse_int(b"4.5"), None);
        assert_eq!(parse_int(b"1/2"), None);
        assert_eq!(line_of(b"a\nb\nc", 4), 3);
    }

    #[test]
    fn lines_strip_cr() {
        let mut l = Lines::new(b"a b\r\n\nc", 0);
        assert_eq!(l.next_line(), Some((0, &b"a b"[..])));
        assert_eq!(l.next_line(), Some((5, &b""[..])));
        assert_eq!(l.next_line(), Some((6, &b"c"[..])));
        assert_eq!(l.next_line(), None);
        assert_eq!(words(b" f 1/2  3 ").collect::<Vec<_>>(), vec![&b"f"[..], b"1/2", b"3"]);
    }
}
