//! Whitespace-separated tokens of an ASCII mesh file (PLY bodies, STL), each with the line it
//! starts on, so that every parse error can name its line.

/// A cursor over the tokens of `data`.
pub(crate) struct Tokens<'a> {
    data: &'a [u8],
    /// Byte offset of the next token (or of the whitespace before it).
    pub(crate) pos: usize,
    /// Line of `pos` (1-based, counted from where the data starts).
    pub(crate) line: usize,
}

impl<'a> Tokens<'a> {
    /// Tokens of `data`, whose first byte is on line `line`.
    pub(crate) fn new(data: &'a [u8], line: usize) -> Self {
        Self { data, pos: 0, line }
    }

    /// The next token and its line; `None` at the end.
    pub(crate) fn next(&mut self) -> Option<(&'a [u8], usize)> {
        let b = self.data;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            if b[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= b.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some((&b[start..self.pos], self.line))
    }

    /// Skips the rest of the current line.
    pub(crate) fn skip_line(&mut self) {
        match self.data[self.pos..].iter().position(|&c| c == b'\n') {
            Some(i) => {
                self.pos += i + 1;
                self.line += 1;
            }
            None => self.pos = self.data.len(),
        }
    }
}
