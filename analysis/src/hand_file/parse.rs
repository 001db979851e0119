//! Reading one formula of a hand file: numbers, the model's names, `+ - * / ^` (or `**`),
//! parentheses and `sin cos tan sqrt exp log`, with the usual precedence (`-x^2` is `-(x^2)`,
//! `^` binds to the right).
//!
//! The grammar is five operators and a function call, and the messages must point at a column of
//! a line of the user's file, so it is a small recursive-descent parser rather than a crate.
//!
//! A file is untrusted input, so what one formula can cost is bounded while it is read: nesting
//! (parentheses, calls, powers, signs, the factors of a product) deeper than [`MAX_DEPTH`], and
//! a tree of more than [`MAX_NODES`] nodes once its `[let]` names are written out, are errors
//! naming the formula. The recursive evaluation, simplification and drop of a tree therefore
//! cannot overflow the stack or run for minutes. A long sum is read as a balanced tree (its
//! depth is the logarithm of its length), so a flat sum of 50,000 terms reads and evaluates.

use std::collections::BTreeMap;

use super::expr::{Expr, Func};

/// Deepest a formula may nest: parentheses, function calls, powers, signs and the factors of a
/// product each count one level; the terms of a sum count the logarithm of their number.
pub const MAX_DEPTH: usize = 200;

/// Most nodes (numbers, names, operations) one formula may have with its `[let]` names written
/// out: a let used twice counts twice (lets that use each other twice over grow exponentially).
pub const MAX_NODES: usize = 200_000;

/// Most nodes all the formulas read with one [`Scope`] may have together (a hand file's): an
/// audit evaluates each a few thousand times.
pub const MAX_FILE_NODES: usize = 1_000_000;

/// A sum of more terms than this is read as a balanced tree; a shorter one keeps the order of
/// evaluation from left to right (bit for bit what it was).
const BALANCE_OVER: usize = 32;

/// Why a formula does not read, and where (0-based character offset in the formula).
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    pub offset: usize,
    pub message: String,
}

/// How deep and how large a tree is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Shape {
    depth: usize,
    nodes: usize,
}

impl Shape {
    const LEAF: Shape = Shape { depth: 1, nodes: 1 };

    /// The shape of any tree, without recursion (a tree built elsewhere may be deep).
    fn of(expr: &Expr) -> Shape {
        let mut shape = Shape { depth: 0, nodes: 0 };
        let mut stack = vec![(expr, 1)];
        while let Some((e, depth)) = stack.pop() {
            shape.nodes += 1;
            shape.depth = shape.depth.max(depth);
            stack.extend(e.children().into_iter().flatten().map(|c| (c, depth + 1)));
        }
        shape
    }
}

/// The names a formula may use: state, input, parameter and `[let]` names, and `pi`, each with
/// the shape of its tree (a `[let]` is written out where it is used).
#[derive(Debug, Clone, Default)]
pub struct Scope {
    names: BTreeMap<String, (Expr, Shape)>,
    /// Nodes of the formulas read with this scope so far (against [`MAX_FILE_NODES`]).
    spent: std::cell::Cell<usize>,
}

impl Scope {
    /// No names.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds (or replaces) `name`.
    pub fn insert(&mut self, name: String, expr: Expr) {
        let shape = Shape::of(&expr);
        self.names.insert(name, (expr, shape));
    }

    /// Whether `name` is known.
    pub fn contains_key(&self, name: &str) -> bool {
        self.names.contains_key(name)
    }
}

/// A tree read so far, with its shape.
struct Node {
    expr: Expr,
    shape: Shape,
}

/// A binary operation's tree.
fn binary(op: char, a: Expr, b: Expr) -> Expr {
    let (a, b) = (Box::new(a), Box::new(b));
    match op {
        '+' => Expr::Add(a, b),
        '-' => Expr::Sub(a, b),
        '*' => Expr::Mul(a, b),
        '/' => Expr::Div(a, b),
        _ => Expr::Pow(a, b),
    }
}

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
            let value = literal
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| ParseError {
                    offset: start,
                    message: format!("`{literal}` is not a finite number"),
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
    /// How many `unary` calls are open: every recursion of the grammar passes through one.
    nesting: usize,
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

    fn too_deep(&self) -> ParseError {
        self.error(format!(
            "the formula nests deeper than {MAX_DEPTH} levels (parentheses, calls, powers, signs \
             and the factors of a product each count one)"
        ))
    }

    fn file_too_large(&self) -> ParseError {
        self.error(format!(
            "the file's formulas have more than {MAX_FILE_NODES} numbers, names and operations \
             with their [let] names written out"
        ))
    }

    /// `shape`, or the error when it is over a limit.
    fn bounded(&self, shape: Shape) -> Result<Shape, ParseError> {
        if shape.depth > MAX_DEPTH {
            return Err(self.too_deep());
        }
        if shape.nodes > MAX_NODES {
            return Err(self.error(format!(
                "the formula has more than {MAX_NODES} numbers, names and operations with its \
                 [let] names written out"
            )));
        }
        Ok(shape)
    }

    /// `a op b`, its shape checked.
    fn combine(&self, op: char, a: Node, b: Node) -> Result<Node, ParseError> {
        let shape = self.bounded(Shape {
            depth: 1 + a.shape.depth.max(b.shape.depth),
            nodes: 1 + a.shape.nodes + b.shape.nodes,
        })?;
        Ok(Node {
            expr: binary(op, a.expr, b.expr),
            shape,
        })
    }

    /// `-a` or `f(a)`, its shape checked.
    fn wrap(&self, a: Node, make: impl FnOnce(Box<Expr>) -> Expr) -> Result<Node, ParseError> {
        let shape = self.bounded(Shape {
            depth: a.shape.depth + 1,
            nodes: a.shape.nodes + 1,
        })?;
        Ok(Node {
            expr: make(Box::new(a.expr)),
            shape,
        })
    }

    /// `term (+|- term)*`: left-associative, or a balanced tree when long.
    fn sum(&mut self) -> Result<Node, ParseError> {
        let first = self.product()?;
        let mut nodes = first.shape.nodes;
        let mut terms = vec![('+', first)];
        while let Some(op) = self.peek_op().filter(|c| matches!(c, '+' | '-')) {
            self.at += 1;
            let term = self.product()?;
            // Checked as the terms come, so a let used 10,000 times is refused before it is
            // copied 10,000 times.
            nodes += term.shape.nodes + 1;
            self.bounded(Shape { depth: 0, nodes })?;
            terms.push((op, term));
        }
        if terms.len() > BALANCE_OVER {
            return self.balanced(terms);
        }
        let mut terms = terms.into_iter();
        let (_, first) = terms.next().expect("one term");
        terms.try_fold(first, |acc, (op, term)| self.combine(op, acc, term))
    }

    /// `t0 ± t1 ± …` (the first sign `+`) as a tree of depth log2(n): a - b + c - d is
    /// (a - b) + (c - d), and a - (b - c) carries the flipped signs of its right half.
    fn balanced(&self, mut terms: Vec<(char, Node)>) -> Result<Node, ParseError> {
        if terms.len() == 1 {
            return Ok(terms.pop().expect("one term").1);
        }
        let right = terms.split_off(terms.len() / 2);
        let op = right[0].0;
        let right: Vec<(char, Node)> = right
            .into_iter()
            .enumerate()
            .map(|(i, (o, t))| match (i, op, o) {
                (0, _, _) => ('+', t),
                (_, '-', '+') => ('-', t),
                (_, '-', _) => ('+', t),
                (_, _, o) => (o, t),
            })
            .collect();
        let (left, right) = (self.balanced(terms)?, self.balanced(right)?);
        self.combine(op, left, right)
    }

    /// `factor (*|/ factor)*`, left-associative (a / b / c is not a / (b / c)).
    fn product(&mut self) -> Result<Node, ParseError> {
        let mut acc = self.unary()?;
        while let Some(op) = self.peek_op().filter(|c| matches!(c, '*' | '/')) {
            self.at += 1;
            let factor = self.unary()?;
            acc = self.combine(op, acc, factor)?;
        }
        Ok(acc)
    }

    fn unary(&mut self) -> Result<Node, ParseError> {
        self.nesting += 1;
        if self.nesting > MAX_DEPTH {
            return Err(self.too_deep());
        }
        let node = match self.peek_op() {
            Some('-') => {
                self.at += 1;
                let a = self.unary()?;
                self.wrap(a, Expr::Neg)
            }
            Some('+') => {
                self.at += 1;
                self.unary()
            }
            _ => self.power(),
        };
        self.nesting -= 1;
        node
    }

    fn power(&mut self) -> Result<Node, ParseError> {
        let base = self.atom()?;
        if self.peek_op() == Some('^') {
            self.at += 1;
            let exponent = self.unary()?;
            return self.combine('^', base, exponent);
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Node, ParseError> {
        let Some((offset, token)) = self.tokens.get(self.at).cloned() else {
            return Err(self.error("the formula ends where a value is expected"));
        };
        self.at += 1;
        match token {
            Token::Num(v) => Ok(Node {
                expr: Expr::Num(v),
                shape: Shape::LEAF,
            }),
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
                    return self.wrap(arg, |a| Expr::Call(func, a));
                }
                let (expr, shape) = self.scope.names.get(&name).ok_or_else(|| ParseError {
                    offset,
                    message: format!(
                        "unknown name `{name}` (not a state, input, parameter or [let] name)"
                    ),
                })?;
                let shape = self.bounded(*shape)?;
                if self.scope.spent.get() + shape.nodes > MAX_FILE_NODES {
                    return Err(self.file_too_large());
                }
                Ok(Node {
                    expr: expr.clone(),
                    shape,
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
        nesting: 0,
    };
    let node = parser.sum()?;
    if parser.at < parser.tokens.len() {
        return Err(parser.error("unexpected text after the formula"));
    }
    let spent = scope.spent.get() + node.shape.nodes;
    if spent > MAX_FILE_NODES {
        return Err(parser.file_too_large());
    }
    scope.spent.set(spent);
    Ok(node.expr)
}

/// The names a formula uses (functions excluded), in order of appearance, for ordering `[let]`
/// names by what they use; `None` when it does not tokenise (the parse will say why).
pub fn names_used(text: &str) -> Option<Vec<String>> {
    let tokens = tokens(text).ok()?;
    let mut out = Vec::new();
    for (i, (_, t)) in tokens.iter().enumerate() {
        if let Token::Name(n) = t {
            let is_call = matches!(tokens.get(i + 1), Some((_, Token::Op('('))));
            if !is_call {
                out.push(n.clone());
            }
        }
    }
    Some(out)
}
