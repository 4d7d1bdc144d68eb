//! The expression parser: text such as `"(x^2 + y^2 + z^2 + 3.75)^2 - 16 (x^2 + y^2)"`
//! expanded exactly into a [`Poly3`] by recursive descent, errors naming the character.

use super::poly::{MAX_DEGREE, Poly3, PolyMap, map_add, map_constant, map_mul, map_pow, map_scale, map_var};
use crate::ShapeError;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Tok {
    /// A number, and whether its literal was a plain unsigned integer.
    Num(f64, bool),
    Var(usize),
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    End,
}

fn parse_err(pos: usize, msg: impl std::fmt::Display) -> ShapeError {
    ShapeError::Invalid(format!("polynomial syntax error at character {pos}: {msg}"))
}

/// Tokens with their 1-based character positions.
fn tokenize(s: &str) -> Result<Vec<(Tok, usize)>, ShapeError> {
    let chars: Vec<char> = s.chars().collect();
    let mut toks = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let ch = chars[i];
        let pos = i + 1;
        let simple = match ch {
            c if c.is_whitespace() => {
                i += 1;
                continue;
            }
            '+' => Some(Tok::Plus),
            '-' => Some(Tok::Minus),
            '*' => Some(Tok::Star),
            '/' => Some(Tok::Slash),
            '^' => Some(Tok::Caret),
            '(' => Some(Tok::LParen),
            ')' => Some(Tok::RParen),
            'x' | 'X' => Some(Tok::Var(0)),
            'y' | 'Y' => Some(Tok::Var(1)),
            'z' | 'Z' => Some(Tok::Var(2)),
            _ => None,
        };
        if let Some(t) = simple {
            toks.push((t, pos));
            i += 1;
            continue;
        }
        if ch.is_ascii_digit() || ch == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // Exponent: e/E, optional sign, at least one digit.
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    while j < chars.len() && chars[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                } else {
                    return Err(parse_err(i + 1, "exponent of a number needs digits"));
                }
            }
            let text: String = chars[start..i].iter().collect();
            let v: f64 = text.parse().map_err(|_| parse_err(pos, format!("invalid number '{text}'")))?;
            if !v.is_finite() {
                return Err(parse_err(pos, format!("number '{text}' is out of range")));
            }
            let integer = text.chars().all(|c| c.is_ascii_digit());
            toks.push((Tok::Num(v, integer), pos));
            continue;
        }
        return Err(parse_err(pos, format!("unexpected character '{ch}'")));
    }
    toks.push((Tok::End, chars.len() + 1));
    Ok(toks)
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    at: usize,
}

impl Parser {
    fn peek(&self) -> (Tok, usize) {
        self.toks[self.at]
    }

    fn bump(&mut self) -> (Tok, usize) {
        let t = self.toks[self.at];
        if t.0 != Tok::End {
            self.at += 1;
        }
        t
    }

    /// expr := ['+'|'-'] term {('+'|'-') term}  (the sign is handled by `unary`).
    fn expr(&mut self) -> Result<PolyMap, ShapeError> {
        let mut acc = self.term()?;
        loop {
            let sign = match self.peek().0 {
                Tok::Plus => 1.0,
                Tok::Minus => -1.0,
                _ => return Ok(acc),
            };
            self.bump();
            let t = self.term()?;
            acc = map_add(acc, &t, sign);
        }
    }

    /// term := unary {('*' unary) | ('/' unary) | power}: explicit or implicit
    /// (juxtaposition) products, and division by non-zero constants.
    fn term(&mut self) -> Result<PolyMap, ShapeError> {
        let mut acc = self.unary()?;
        loop {
            let (tok, pos) = self.peek();
            let rhs = match tok {
                Tok::Star => {
                    self.bump();
                    self.unary()?
                }
                Tok::Slash => {
                    self.bump();
                    let at = self.peek().1;
                    let div = self.unary()?;
                    let c = match (div.len(), div.get(&[0, 0, 0])) {
                        (1, Some(&c)) => c,
                        _ => return Err(parse_err(at, "division only by a non-zero number")),
                    };
                    let q = 1.0 / c;
                    if !q.is_finite() {
                        return Err(parse_err(at, "division by a number too close to zero"));
                    }
                    acc = map_scale(acc, q);
                    continue;
                }
                Tok::Num(..) | Tok::Var(_) | Tok::LParen => self.power()?,
                _ => return Ok(acc),
            };
            acc = map_mul(&acc, &rhs)
                .ok_or_else(|| parse_err(pos, format!("product exceeds the maximum degree {MAX_DEGREE}")))?;
        }
    }

    /// unary := ('+'|'-') unary | power.
    fn unary(&mut self) -> Result<PolyMap, ShapeError> {
        match self.peek().0 {
            Tok::Minus => {
                self.bump();
                Ok(map_scale(self.unary()?, -1.0))
            }
            Tok::Plus => {
                self.bump();
                self.unary()
            }
            _ => self.power(),
        }
    }

    /// power := primary ['^' unsigned-integer].
    fn power(&mut self) -> Result<PolyMap, ShapeError> {
        let base = self.primary()?;
        if self.peek().0 != Tok::Caret {
            return Ok(base);
        }
        let (_, caret) = self.bump();
        match self.bump() {
            (Tok::Num(v, true), pos) => {
                if v > MAX_DEGREE as f64 {
                    return Err(parse_err(pos, format!("exponent {v} exceeds the maximum degree {MAX_DEGREE}")));
                }
                map_pow(&base, v as u32)
                    .ok_or_else(|| parse_err(caret, format!("power exceeds the maximum degree {MAX_DEGREE}")))
            }
            (_, pos) => Err(parse_err(pos, "expected a non-negative integer exponent after '^'")),
        }
    }

    /// primary := number | x | y | z | '(' expr ')'.
    fn primary(&mut self) -> Result<PolyMap, ShapeError> {
        match self.bump() {
            (Tok::Num(v, _), _) => Ok(map_constant(v)),
            (Tok::Var(a), _) => Ok(map_var(a)),
            (Tok::LParen, open) => {
                let inner = self.expr()?;
                match self.bump() {
                    (Tok::RParen, _) => Ok(inner),
                    (_, pos) => Err(parse_err(pos, format!("expected ')' to close the '(' at character {open}"))),
                }
            }
            (Tok::End, pos) => Err(parse_err(pos, "unexpected end of input")),
            (t, pos) => Err(parse_err(pos, format!("unexpected {}", tok_name(t)))),
        }
    }
}

fn tok_name(t: Tok) -> &'static str {
    match t {
        Tok::Num(..) => "number",
        Tok::Var(_) => "variable",
        Tok::Plus => "'+'",
        Tok::Minus => "'-'",
        Tok::Star => "'*'",
        Tok::Slash => "'/'",
        Tok::Caret => "'^'",
        Tok::LParen => "'('",
        Tok::RParen => "')'",
        Tok::End => "end of input",
    }
}

/// Parses a polynomial in x, y, z, e.g. `"(x^2 + y^2 + z^2 + 3.75)^2 - 16 (x^2 + y^2)"`.
///
/// Grammar: sums and differences of products; factors are numbers (`2`, `3.5`, `1e-3`),
/// the variables `x`, `y`, `z`, or parenthesised sub-expressions, each optionally raised
/// to a non-negative integer power `^n`; products by `*` or by juxtaposition (`2 x y`,
/// `2xy`); division by a non-zero constant (`9/4 y^2`, `x^2/(2^2)`); unary `-`/`+`.
/// Everything is expanded exactly by polynomial arithmetic.
/// Errors name the (1-based) character position: unknown characters, `x^^2`, `x^-1`,
/// `x^2.5`, `1/x`, unbalanced parentheses, numbers that overflow (`1e999`), a degree above
/// [`MAX_DEGREE`], or a polynomial that is identically zero.
pub fn parse(s: &str) -> Result<Poly3, ShapeError> {
    let mut p = Parser { toks: tokenize(s)?, at: 0 };
    let map = p.expr()?;
    match p.peek() {
        (Tok::End, _) => {}
        (Tok::RParen, pos) => return Err(parse_err(pos, "unmatched ')'")),
        (t, pos) => return Err(parse_err(pos, format!("unexpected {}", tok_name(t)))),
    }
    Poly3::from_map(map)
}
