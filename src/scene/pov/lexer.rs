//! POV-Ray SDL tokens with their file, line and column. Keywords and identifiers are both
//! `Word`s: POV-Ray's keywords are reserved, but which words are keywords depends on where they
//! stand, so the parser decides.

use super::{Pos, PovError};

#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    Num(f64),
    Str(String),
    Word(String),
    /// `#declare`, `#if`, ...: the word after `#` (POV-Ray allows spaces between them).
    Directive(String),
    /// Punctuation and operators, one or two characters: `{ } ( ) [ ] < > <= >= != = + - * / , ; . ? : ! & |`.
    Sym(&'static str),
}

#[derive(Clone, Debug)]
pub struct Token {
    pub tok: Tok,
    pub pos: Pos,
}

const SYMBOLS: [&str; 23] = [
    "<=", ">=", "!=", "{", "}", "(", ")", "[", "]", "<", ">", "=", "+", "-", "*", "/", ",", ";", ".", "?", ":", "!",
    "&",
];

/// Splits `text` (file number `file`) into tokens. Comments (`//` and nested `/* */`) are dropped.
pub fn lex(text: &str, file: u32) -> Result<Vec<Token>, PovError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0usize, 1u32, 1u32);
    // Advances over one character, counting lines and columns.
    let step = |i: &mut usize, line: &mut u32, col: &mut u32| {
        if chars[*i] == '\n' {
            *line += 1;
            *col = 1;
        } else {
            *col += 1;
        }
        *i += 1;
    };
    while i < chars.len() {
        let c = chars[i];
        let pos = Pos { file, line, col };
        if c.is_whitespace() {
            step(&mut i, &mut line, &mut col);
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                step(&mut i, &mut line, &mut col);
            }
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'*') {
            // POV-Ray's block comments nest.
            let mut depth = 0;
            loop {
                if i >= chars.len() {
                    return Err(PovError::at(pos, "this /* comment is never closed; add */".into()));
                }
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    step(&mut i, &mut line, &mut col);
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    step(&mut i, &mut line, &mut col);
                    if depth == 0 {
                        step(&mut i, &mut line, &mut col);
                        break;
                    }
                }
                step(&mut i, &mut line, &mut col);
            }
            continue;
        }
        if c == '"' {
            step(&mut i, &mut line, &mut col);
            let mut s = String::new();
            loop {
                let Some(&d) = chars.get(i) else {
                    return Err(PovError::at(pos, "this string is never closed; add a closing \"".into()));
                };
                if d == '\n' {
                    return Err(PovError::at(pos, "a string cannot span lines; close it with \" on this line".into()));
                }
                step(&mut i, &mut line, &mut col);
                if d == '"' {
                    break;
                }
                if d == '\\' {
                    let Some(&e) = chars.get(i) else { continue };
                    step(&mut i, &mut line, &mut col);
                    s.push(match e {
                        'n' => '\n',
                        't' => '\t',
                        'r' => '\r',
                        'a' | 'b' | 'f' | 'v' => ' ',
                        other => other,
                    });
                } else {
                    s.push(d);
                }
            }
            out.push(Token { tok: Tok::Str(s), pos });
            continue;
        }
        if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit())) {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                step(&mut i, &mut line, &mut col);
            }
            // An exponent only when digits follow (`1e` alone is not a number).
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    while i < j {
                        step(&mut i, &mut line, &mut col);
                    }
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        step(&mut i, &mut line, &mut col);
                    }
                }
            }
            let text: String = chars[start..i].iter().collect();
            let value: f64 = text
                .parse()
                .map_err(|_| PovError::at(pos, format!("`{text}` is not a number; write it as 1.5 or 2e-3")))?;
            out.push(Token { tok: Tok::Num(value), pos });
            continue;
        }
        if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                step(&mut i, &mut line, &mut col);
            }
            out.push(Token { tok: Tok::Word(chars[start..i].iter().collect()), pos });
            continue;
        }
        if c == '#' {
            step(&mut i, &mut line, &mut col);
            while i < chars.len() && (chars[i] == ' ' || chars[i] == '\t') {
                step(&mut i, &mut line, &mut col);
            }
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                step(&mut i, &mut line, &mut col);
            }
            if start == i {
                // POV-Ray 3.7 reads a `#` that no directive follows as nothing
                // (`language/image_size.pov` ends a camera with `look_at <0,2,0>#`).
                continue;
            }
            out.push(Token { tok: Tok::Directive(chars[start..i].iter().collect()), pos });
            continue;
        }
        if c == '|' {
            step(&mut i, &mut line, &mut col);
            out.push(Token { tok: Tok::Sym("|"), pos });
            continue;
        }
        let two: String = chars[i..(i + 2).min(chars.len())].iter().collect();
        if let Some(sym) = SYMBOLS.iter().find(|s| s.len() == 2 && **s == two) {
            step(&mut i, &mut line, &mut col);
            step(&mut i, &mut line, &mut col);
            out.push(Token { tok: Tok::Sym(sym), pos });
            continue;
        }
        if let Some(sym) = SYMBOLS.iter().find(|s| s.len() == 1 && s.starts_with(c)) {
            step(&mut i, &mut line, &mut col);
            out.push(Token { tok: Tok::Sym(sym), pos });
            continue;
        }
        return Err(PovError::at(pos, format!("unexpected character {c:?}")));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_carry_line_and_column() {
        let toks = lex("#declare A = <1, .5e1>; /* a /* nested */ c */\n  sphere // x\n \"s\\\"t\"", 0).unwrap();
        let kinds: Vec<_> = toks.iter().map(|t| t.tok.clone()).collect();
        assert_eq!(kinds[0], Tok::Directive("declare".into()));
        assert_eq!(kinds[4], Tok::Num(1.0));
        assert_eq!(kinds[6], Tok::Num(5.0));
        let sphere = toks.iter().find(|t| t.tok == Tok::Word("sphere".into())).unwrap();
        assert_eq!((sphere.pos.line, sphere.pos.col), (2, 3));
        assert_eq!(toks.last().unwrap().tok, Tok::Str("s\"t".into()));
    }

    #[test]
    fn unclosed_comment_and_string_are_errors() {
        assert!(lex("/* x", 0).is_err());
        assert!(lex("\"abc", 0).is_err());
        assert!(lex("a ` b", 0).is_err());
    }
}
