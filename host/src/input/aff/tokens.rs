//! The AFF tokenizer: whitespace-separated words with their line numbers, `#` and `%`
//! comments to the end of the line, and braces as words of their own (BART writes
//! `{` and `}` on their own lines, but nothing in the format needs them spaced).

use anyhow::{anyhow, bail, Result};

/// A word and the line it is on.
#[derive(Clone, Copy, Debug)]
pub struct Token<'t> {
    /// The word.
    pub text: &'t str,
    /// 1-based line number.
    pub line: u32,
}

/// The words of one file, read front to back.
pub struct Tokens<'t> {
    words: Vec<Token<'t>>,
    at: usize,
    /// The file's name, for messages.
    pub name: String,
    last_line: u32,
}

impl<'t> Tokens<'t> {
    /// Splits `text` (the file `name`) into words.
    pub fn new(name: &str, text: &'t str) -> Tokens<'t> {
        let mut words = Vec::new();
        for (n, raw) in text.lines().enumerate() {
            let line = raw.split(['#', '%']).next().unwrap_or("");
            for word in line.split_whitespace() {
                // Braces stand alone even when written against a word.
                let mut rest = word;
                while !rest.is_empty() {
                    let cut = rest.find(['{', '}']).unwrap_or(rest.len());
                    let (head, tail) = if cut == 0 { rest.split_at(1) } else { rest.split_at(cut) };
                    words.push(Token { text: head, line: n as u32 + 1 });
                    rest = tail;
                }
            }
        }
        let last_line = text.lines().count() as u32;
        Tokens { words, at: 0, name: name.to_string(), last_line }
    }

    /// The next word, if any, without taking it.
    pub fn peek(&self) -> Option<Token<'t>> {
        self.words.get(self.at).copied()
    }

    /// Takes the next word, if any.
    pub fn next_token(&mut self) -> Option<Token<'t>> {
        let t = self.peek()?;
        self.at += 1;
        Some(t)
    }

    /// Words left.
    pub fn remaining(&self) -> usize {
        self.words.len() - self.at
    }

    /// The line of the next word (or the last line at the end), for messages.
    pub fn line(&self) -> u32 {
        self.peek().map_or(self.last_line, |t| t.line)
    }

    /// The line of the word just taken.
    pub fn previous_line(&self) -> u32 {
        self.at.checked_sub(1).and_then(|i| self.words.get(i)).map_or(1, |t| t.line)
    }

    /// An error at the current line.
    pub fn error(&self, what: impl std::fmt::Display) -> anyhow::Error {
        anyhow!("{}:{}: {what}", self.name, self.line())
    }

    /// Takes a word that `what` needs.
    pub fn word(&mut self, what: &str) -> Result<&'t str> {
        match self.next_token() {
            Some(t) => Ok(t.text),
            None => Err(anyhow!("{}:{}: the file ends before {what}", self.name, self.last_line)),
        }
    }

    /// Takes a finite number.
    pub fn number(&mut self, what: &str) -> Result<f64> {
        let line = self.line();
        let w = self.word(what)?;
        let v: f64 = w.parse().map_err(|_| anyhow!("{}:{line}: {what}: '{w}' is not a number", self.name))?;
        if !v.is_finite() {
            bail!("{}:{line}: {what}: {w} is not a finite number", self.name);
        }
        Ok(v)
    }

    /// Takes three finite numbers.
    pub fn vec3(&mut self, what: &str) -> Result<[f64; 3]> {
        Ok([self.number(what)?, self.number(what)?, self.number(what)?])
    }

    /// Takes a count no larger than the words left divided by `words_each` (so a count
    /// cannot make a reader allocate for data that is not there).
    pub fn count(&mut self, what: &str, words_each: usize) -> Result<usize> {
        let line = self.line();
        let w = self.word(what)?;
        let n: usize = w.parse().map_err(|_| anyhow!("{}:{line}: {what}: '{w}' is not a count", self.name))?;
        if n.saturating_mul(words_each.max(1)) > self.remaining() {
            bail!("{}:{line}: {what}: {n} is more than the file holds", self.name);
        }
        Ok(n)
    }

    /// Takes `{`.
    pub fn open(&mut self, what: &str) -> Result<()> {
        let line = self.line();
        match self.word(what)? {
            "{" => Ok(()),
            w => Err(anyhow!("{}:{line}: {what}: expected '{{', found '{w}'", self.name)),
        }
    }
}
