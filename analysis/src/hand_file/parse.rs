//! Reading one formula of a hand file: numbers, the model's names, `+ - * / ^` (or `**`),
//! parentheses and `sin cos tan sqrt exp log`, with the usual precedence (`-x^2` is `-(x^2)`,
//! `^` binds to the right).
//!
//! The grammar is five operators and a function call, and the messages must point at a column of
//! a line of the user's file, so it is a small recursive-descent parser rather than a crate.

use std::collections::BTreeMap;

use super::expr::{Expr, Func};

/// Why a formula does not read, and where (0-based character offset in the formula).
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    pub offset: usize,
    pub message: String,
}

/// The names a formula may use: state, input, parameter and `[let]` names, and `pi`.
pub type Scope = BTreeMap<String, Expr>;

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Num(f64),
    Name(String),
    Op(char),
}

fn tokens(text: &str) -> Result<Vec<(usize, Token)>, ParseError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let start = i;
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let literal: String = chars[start..i].iter().collect();
            let value = literal.parse::<f64>().map_err(|_| ParseError {
                offset: start,
                message: format!("`{literal}` is not a number"),
            })?;
            out.push((start, Token::Num(value)));
        } else if c.is_alphabetic() || c == '_' {
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((start, Token::Name(chars[start..i].iter().collect())));
        } else if c == '*' && chars.get(i + 1) == Some(&'*') {
            out.push((start, Token::Op('^')));
            i += 2;
        } else if "+-*/^(),".contains(c) {
            out.push((start, Token::Op(c)));
            i += 1;
        } else {
            return Err(ParseError {
                offset: start,
                message: format!("unexpected character `{c}`"),
            });
        }
    }
    Ok(out)
}

struct Parser<'a> {
    tokens: Vec<(usize, Token)>,
    at: usize,
    end: usize,
    scope: &'a Scope,
}

impl Parser<'_> {
    fn offset(&self) -> usize {
        self.tokens.get(self.at).map_or(self.end, |t| t.0)
    }

    fn error(&self, message: impl Into<String>) -> ParseError {
        ParseError {
            offset: self.offset(),
            message: message.into(),
        }
    }

    fn peek_op(&self) -> Option<char> {
        match self.tokens.get(self.at) {
            Some((_, Token::Op(c))) => Some(*c),
            _ => None,
        }
    }

    fn expect(&mut self, op: char) -> Result<(), ParseError> {
        if self.peek_op() == Some(op) {
            self.at += 1;
            Ok(())
        } else {
            Err(self.error(format!("expected `{op}`")))
        }
    }

    /// One left-associative level: `next (op next)*` for the operators `ops`.
    fn level(
        &mut self,
        ops: [char; 2],
        next: fn(&mut Self) -> Result<Expr, ParseError>,
    ) -> Result<Expr, ParseError> {
        let mut acc = next(self)?;
        while let Some(op) = self.peek_op().filter(|c| ops.contains(c)) {
            self.at += 1;
            let (a, b) = (Box::new(acc), Box::new(next(self)?));
            acc = match op {
                '+' => Expr::Add(a, b),
                '-' => Expr::Sub(a, b),
                '*' => Expr::Mul(a, b),
                _ => Expr::Div(a, b),
            };
        }
        Ok(acc)
    }

    fn sum(&mut self) -> Result<Expr, ParseError> {
        self.level(['+', '-'], Self::product)
    }

    fn product(&mut self) -> Result<Expr, ParseError> {
        self.level(['*', '/'], Self::unary)
    }

    fn unary(&mut self) -> Result<Expr, ParseError> {
        match self.peek_op() {
            Some('-') => {
                self.at += 1;
                Ok(Expr::Neg(Box::new(self.unary()?)))
            }
            Some('+') => {
                self.at += 1;
                self.unary()
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Expr, ParseError> {
        let base = self.atom()?;
        if self.peek_op() == Some('^') {
            self.at += 1;
            let exponent = self.unary()?;
            return Ok(Expr::Pow(Box::new(base), Box::new(exponent)));
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Expr, ParseError> {
        let Some((offset, token)) = self.tokens.get(self.at).cloned() else {
            return Err(self.error("the formula ends where a value is expected"));
        };
        self.at += 1;
        match token {
            Token::Num(v) => Ok(Expr::Num(v)),
            Token::Op('(') => {
                let inner = self.sum()?;
                self.expect(')')?;
                Ok(inner)
            }
            Token::Op(c) => {
                self.at -= 1;
                Err(self.error(format!("unexpected `{c}`")))
            }
            Token::Name(name) => {
                if self.peek_op() == Some('(') {
                    let func = Func::from_name(&name).ok_or_else(|| ParseError {
                        offset,
                        message: format!(
                            "unknown function `{name}` (known: sin, cos, tan, sqrt, exp, log)"
                        ),
                    })?;
                    self.at += 1;
                    let arg = self.sum()?;
                    self.expect(')')?;
                    return Ok(Expr::Call(func, Box::new(arg)));
                }
                self.scope.get(&name).cloned().ok_or_else(|| ParseError {
                    offset,
                    message: format!(
                        "unknown name `{name}` (not a state, input, parameter or [let] name)"
                    ),
                })
            }
        }
    }
}

/// Parses one formula with the names of `scope`.
pub fn parse(text: &str, scope: &Scope) -> Result<Expr, ParseError> {
    let tokens = tokens(text)?;
    let mut parser = Parser {
        tokens,
        at: 0,
        end: text.chars().count(),
        scope,
    };
    let expr = parser.sum()?;
    if parser.at < parser.tokens.len() {
        return Err(parser.error("unexpected text after the formula"));
    }
    Ok(expr)
}
