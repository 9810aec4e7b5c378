//! Expressions in the parameters `u`, `v` and the time `t`: parsing, evaluation and exact
//! symbolic differentiation.
//!
//! What: the boundary functions G_ik(v, t) of `dynamic-pde-surfaces.txt` eq (2), the shape
//! functions b_i, c_i, d_i, the density rho and the damping eta of eq (1) (section V-B, V-C), the
//! side conditions of eq (33) and the local-deformation functions p_i of eqs (31)-(32) are all
//! written by the user as expressions such as `4.763 + 0.017*sin(v) - 3.395*exp(0.1*v)`.
//!
//! How: a recursive-descent parser builds an [`Expr`] tree; named parameters (`a`, `r0p`, ...)
//! are replaced by their numbers while parsing, so a parsed tree holds only numbers, the three
//! variables and the operators. [`Expr::derivative`] differentiates the tree exactly with the
//! usual rules (sum, product, quotient, power and chain rules), simplifying as it goes (constant
//! folding, `0 * x = 0`, `1 * x = x`, ...), which is what the collocation method needs for
//! d2/dv2, d4/dv4, d/dt and d2/dt2 of every basic function (eq 7-8).
//!
//! Grammar (usual precedence, `^` binds tighter than unary minus and is right-associative, so
//! `-v^2 = -(v^2)` and `2^3^2 = 2^9`):
//! ```text
//! expr   := term (('+' | '-') term)*
//! term   := unary (('*' | '/') unary)*
//! unary  := ('-' | '+') unary | power
//! power  := atom ('^' unary)?
//! atom   := number | name | name '(' expr ')' | '(' expr ')'
//! ```
//! Functions: `sin cos tan exp ln log sqrt sinh cosh` (`log` is the natural logarithm, as `ln`).
//! Constant: `pi`. Variables: `u`, `v`, `t`. Numbers: `3`, `0.5`, `.5`, `1e-3`.
//!
//! Limitations: no implicit multiplication (`2v` is an error: write `2*v`); no user functions.
//! Errors carry the 1-based column (in characters) of the offending place.
//!
//! Size limits (issue 17): the parser, the evaluator and the differentiator recurse on the
//! tree, so an expression has at most [`MAX_TOKENS`] tokens and a tree at most [`MAX_DEPTH`]
//! deep (a chain `v+v+...+v` of 30,000 terms or 30,000 unary minuses overflowed the stack);
//! [`Expr::try_derivative`] bounds the size and depth of a derivative before building it
//! ([`MAX_DERIVED_NODES`], [`MAX_DERIVED_DEPTH`]: `v^v^...^v` doubles with every level). A
//! constant part that folds to a non-finite number (`1/0`, `0/0`, `0*(1/0)`, `exp(1000)`,
//! `1e400`) is an error at its column.

use std::fmt;

/// One of the three independent variables of a PDE surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Var {
    /// The first surface parameter, 0 <= u <= 1 (the direction of the fourth-order ODE).
    U,
    /// The second surface parameter, v0 <= v <= v1 (the direction of the boundary curves).
    V,
    /// Time.
    T,
}

impl Var {
    fn name(self) -> &'static str {
        match self {
            Var::U => "u",
            Var::V => "v",
            Var::T => "t",
        }
    }
}

/// A built-in function of one argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    /// sine
    Sin,
    /// cosine
    Cos,
    /// tangent
    Tan,
    /// exponential
    Exp,
    /// natural logarithm (`ln` or `log`)
    Ln,
    /// square root
    Sqrt,
    /// hyperbolic sine
    Sinh,
    /// hyperbolic cosine
    Cosh,
}

/// Names accepted for functions, for error messages.
pub const FUNCTION_NAMES: &str = "sin, cos, tan, exp, ln, log, sqrt, sinh, cosh";

impl Func {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "sin" => Func::Sin,
            "cos" => Func::Cos,
            "tan" => Func::Tan,
            "exp" => Func::Exp,
            "ln" | "log" => Func::Ln,
            "sqrt" => Func::Sqrt,
            "sinh" => Func::Sinh,
            "cosh" => Func::Cosh,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Sqrt => "sqrt",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
        }
    }

    /// Applies the function.
    #[inline]
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Sqrt => x.sqrt(),
            Func::Sinh => x.sinh(),
            Func::Cosh => x.cosh(),
        }
    }
}

/// An expression tree in `u`, `v`, `t`. Parameters are already replaced by numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A number.
    Num(f64),
    /// A variable.
    Var(Var),
    /// `-a`
    Neg(Box<Expr>),
    /// `a + b`
    Add(Box<Expr>, Box<Expr>),
    /// `a - b`
    Sub(Box<Expr>, Box<Expr>),
    /// `a * b`
    Mul(Box<Expr>, Box<Expr>),
    /// `a / b`
    Div(Box<Expr>, Box<Expr>),
    /// `a ^ b`
    Pow(Box<Expr>, Box<Expr>),
    /// `f(a)`
    Call(Func, Box<Expr>),
}

/// What went wrong in an expression.
#[derive(Clone, Debug, PartialEq)]
pub enum ExprErrorKind {
    /// The text is empty.
    Empty,
    /// A character that starts no token.
    UnexpectedChar(char),
    /// A `(` without its `)`.
    UnclosedParen,
    /// A `)` without its `(`.
    UnopenedParen,
    /// A name followed by `(` that is not a known function.
    UnknownFunction(String),
    /// A name that is neither a variable, `pi` nor a parameter.
    UnknownName(String),
    /// A function name not followed by `(`.
    MissingArgument(String),
    /// An operand (number, name, parenthesis) was expected.
    ExpectedOperand,
    /// Something after a complete expression (e.g. `2 v`: implicit multiplication).
    TrailingInput,
    /// A number that does not parse.
    BadNumber(String),
    /// A variable that is not allowed here (e.g. `u` in a boundary function of v and t).
    VariableNotAllowed(&'static str),
    /// Parentheses nested deeper than [`MAX_NESTING`].
    TooDeep,
    /// More than [`MAX_TOKENS`] tokens.
    TooLong,
    /// An expression tree deeper than [`MAX_DEPTH`] (a long chain of operators).
    TooDeepTree {
        /// Its depth.
        depth: usize,
    },
    /// A derivative would exceed [`MAX_DERIVED_NODES`] nodes or [`MAX_DERIVED_DEPTH`] levels.
    DerivativeTooLarge {
        /// The variable.
        var: &'static str,
        /// Upper bound of its node count.
        nodes: f64,
        /// Upper bound of its depth.
        depth: f64,
    },
    /// A constant part folds to a non-finite number (`1/0`, `0/0`, `exp(1000)`).
    NotFinite(f64),
}

/// Deepest parenthesis nesting accepted (the parser is recursive).
pub const MAX_NESTING: usize = 64;

/// Most tokens (numbers, names, operators, parentheses) in one expression: 10,000, far more
/// than a boundary function of the papers (tens) and few enough that every recursion on the
/// tree stays shallow.
pub const MAX_TOKENS: usize = 10_000;

/// Deepest expression tree accepted from text: 256 levels (a sum of 256 terms is 256 deep, as
/// is `-` repeated 256 times or `v^v^...^v` with 256 powers).
pub const MAX_DEPTH: usize = 256;

/// Most nodes of a derivative built by [`Expr::try_derivative`] (an upper bound is checked
/// before it is built): 100,000 nodes, about 4 MB, and 100,000 operations per evaluation.
pub const MAX_DERIVED_NODES: f64 = 100_000.0;

/// Deepest derivative tree [`Expr::try_derivative`] builds: 512 levels. Differentiating,
/// evaluating, cloning, printing and dropping such a tree fits a 2 MB thread stack (the
/// default of spawned threads and rayon's workers) even unoptimized, where differentiation
/// takes about 2 kB of stack per level (tested).
pub const MAX_DERIVED_DEPTH: f64 = 512.0;

/// A parse error with the 1-based character column where it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct ExprError {
    /// 1-based column (in characters) of the offending place.
    pub column: usize,
    /// What is wrong.
    pub kind: ExprErrorKind,
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "column {}: ", self.column)?;
        match &self.kind {
            ExprErrorKind::Empty => write!(f, "empty expression"),
            ExprErrorKind::UnexpectedChar(c) => write!(f, "unexpected character '{c}'"),
            ExprErrorKind::UnclosedParen => {
                write!(f, "unbalanced parentheses: '(' is never closed")
            }
            ExprErrorKind::UnopenedParen => {
                write!(f, "unbalanced parentheses: ')' has no matching '('")
            }
            ExprErrorKind::UnknownFunction(n) => {
                write!(f, "unknown function '{n}' (known: {FUNCTION_NAMES})")
            }
            ExprErrorKind::UnknownName(n) => write!(
                f,
                "unknown name '{n}' (variables are u, v, t; constant pi; or a parameter of the spec)"
            ),
            ExprErrorKind::MissingArgument(n) => {
                write!(f, "function '{n}' needs an argument in parentheses")
            }
            ExprErrorKind::ExpectedOperand => {
                write!(f, "expected a number, a name or '(' here")
            }
            ExprErrorKind::TrailingInput => write!(
                f,
                "unexpected input after a complete expression (missing operator? write 2*v, not 2v)"
            ),
            ExprErrorKind::BadNumber(s) => write!(f, "bad number '{s}'"),
            ExprErrorKind::VariableNotAllowed(what) => write!(f, "{what}"),
            ExprErrorKind::TooDeep => {
                write!(f, "parentheses nested deeper than {MAX_NESTING}")
            }
            ExprErrorKind::TooLong => write!(
                f,
                "the expression has more than {MAX_TOKENS} tokens (numbers, names, operators)"
            ),
            ExprErrorKind::TooDeepTree { depth } => write!(
                f,
                "the expression nests {depth} operations deep (a chain of that many terms or \
                 operators), more than the limit of {MAX_DEPTH}"
            ),
            ExprErrorKind::DerivativeTooLarge { var, nodes, depth } => write!(
                f,
                "its derivative in {var} would have up to {nodes:.2e} nodes and {depth:.0} levels, \
                 more than the limits of {MAX_DERIVED_NODES:.0} nodes and {MAX_DERIVED_DEPTH:.0} \
                 levels; simplify the expression"
            ),
            ExprErrorKind::NotFinite(x) => write!(
                f,
                "this constant part evaluates to {x} (division by zero or overflow)"
            ),
        }
    }
}

impl std::error::Error for ExprError {}

/// At most `max` characters of `text`, with `...` when cut (for error messages).
pub fn shorten(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        text.to_string()
    } else {
        let head: String = text.chars().take(max).collect();
        format!("{head}...")
    }
}

impl ExprError {
    /// The message without the column (for errors about a derived expression).
    pub fn kind_text(&self) -> String {
        let full = self.to_string();
        match full.split_once(": ") {
            Some((_, rest)) => rest.to_string(),
            None => full,
        }
    }

    /// The expression text with a caret under the error column (two lines, no trailing newline).
    ///
    /// A text longer than 80 characters is shown as a window of 80 characters around the
    /// column (`...` marks cuts), so that a 30,000-term expression gives a short message.
    pub fn pointer(&self, text: &str) -> String {
        const WIDTH: usize = 80;
        let chars: Vec<char> = text.chars().collect();
        let col = self.column.saturating_sub(1);
        if chars.len() <= WIDTH {
            return format!("  {text}\n  {}^", " ".repeat(col));
        }
        let start = col.saturating_sub(WIDTH / 2).min(chars.len() - WIDTH);
        let end = (start + WIDTH).min(chars.len());
        let lead = if start > 0 { "..." } else { "" };
        let tail = if end < chars.len() { "..." } else { "" };
        let window: String = chars[start..end].iter().collect();
        format!(
            "  {lead}{window}{tail}\n  {}^",
            " ".repeat(lead.len() + col.saturating_sub(start))
        )
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Op(char),
    Open,
    Close,
}

fn lex(text: &str) -> Result<Vec<(Tok, usize)>, ExprError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    // First check parentheses so that the error points at the unmatched one.
    let mut stack = Vec::new();
    for (k, &c) in chars.iter().enumerate() {
        if c == '(' {
            if stack.len() >= MAX_NESTING {
                return Err(ExprError {
                    column: k + 1,
                    kind: ExprErrorKind::TooDeep,
                });
            }
            stack.push(k);
        } else if c == ')' && stack.pop().is_none() {
            return Err(ExprError {
                column: k + 1,
                kind: ExprErrorKind::UnopenedParen,
            });
        }
    }
    if let Some(&k) = stack.last() {
        return Err(ExprError {
            column: k + 1,
            kind: ExprErrorKind::UnclosedParen,
        });
    }
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        if out.len() >= MAX_TOKENS {
            return Err(ExprError {
                column: col,
                kind: ExprErrorKind::TooLong,
            });
        }
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // Exponent only when followed by a digit (optionally signed).
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
            let s: String = chars[start..i].iter().collect();
            let x: f64 = s
                .parse()
                .ok()
                .filter(|x: &f64| x.is_finite())
                .ok_or_else(|| ExprError {
                    column: col,
                    kind: ExprErrorKind::BadNumber(s.chars().take(40).collect()),
                })?;
            out.push((Tok::Num(x), col));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((Tok::Name(chars[start..i].iter().collect()), col));
        } else if "+-*/^".contains(c) {
            out.push((Tok::Op(c), col));
            i += 1;
        } else if c == '(' {
            out.push((Tok::Open, col));
            i += 1;
        } else if c == ')' {
            out.push((Tok::Close, col));
            i += 1;
        } else {
            return Err(ExprError {
                column: col,
                kind: ExprErrorKind::UnexpectedChar(c),
            });
        }
    }
    Ok(out)
}

struct Parser<'a> {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    end_col: usize,
    params: &'a dyn Fn(&str) -> Option<f64>,
    /// Current recursion depth of `unary` (unary minus and powers recurse).
    nest: usize,
}

/// `e`, or an error at `column` when it is a number that is not finite.
fn finite(e: Expr, column: usize) -> Result<Expr, ExprError> {
    match e {
        Expr::Num(x) if !x.is_finite() => Err(ExprError {
            column,
            kind: ExprErrorKind::NotFinite(x),
        }),
        e => Ok(e),
    }
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|(t, _)| t)
    }
    fn col(&self) -> usize {
        self.toks.get(self.pos).map_or(self.end_col, |(_, c)| *c)
    }
    fn err<T>(&self, kind: ExprErrorKind) -> Result<T, ExprError> {
        Err(ExprError {
            column: self.col(),
            kind,
        })
    }

    fn expr(&mut self) -> Result<Expr, ExprError> {
        let mut a = self.term()?;
        while let Some(Tok::Op(op @ ('+' | '-'))) = self.peek() {
            let op = *op;
            let col = self.col();
            self.pos += 1;
            let b = self.term()?;
            a = finite(if op == '+' { add(a, b) } else { sub(a, b) }, col)?;
        }
        Ok(a)
    }

    fn term(&mut self) -> Result<Expr, ExprError> {
        let mut a = self.unary()?;
        while let Some(Tok::Op(op @ ('*' | '/'))) = self.peek() {
            let op = *op;
            let col = self.col();
            self.pos += 1;
            let b = self.unary()?;
            a = finite(if op == '*' { mul(a, b) } else { div(a, b) }, col)?;
        }
        Ok(a)
    }

    fn unary(&mut self) -> Result<Expr, ExprError> {
        self.nest += 1;
        if self.nest > MAX_DEPTH {
            return self.err(ExprErrorKind::TooDeepTree { depth: self.nest });
        }
        let e = match self.peek() {
            Some(Tok::Op('-')) => {
                self.pos += 1;
                self.unary().map(neg)
            }
            Some(Tok::Op('+')) => {
                self.pos += 1;
                self.unary()
            }
            _ => self.power(),
        };
        self.nest -= 1;
        e
    }

    fn power(&mut self) -> Result<Expr, ExprError> {
        let a = self.atom()?;
        if let Some(Tok::Op('^')) = self.peek() {
            let col = self.col();
            self.pos += 1;
            let b = self.unary()?;
            return finite(pow(a, b), col);
        }
        Ok(a)
    }

    fn atom(&mut self) -> Result<Expr, ExprError> {
        let col = self.col();
        match self.peek().cloned() {
            Some(Tok::Num(x)) => {
                self.pos += 1;
                Ok(Expr::Num(x))
            }
            Some(Tok::Open) => {
                self.pos += 1;
                let e = self.expr()?;
                match self.peek() {
                    Some(Tok::Close) => {
                        self.pos += 1;
                        Ok(e)
                    }
                    _ => self.err(ExprErrorKind::ExpectedOperand),
                }
            }
            Some(Tok::Name(name)) => {
                self.pos += 1;
                if let Some(Tok::Open) = self.peek() {
                    let Some(f) = Func::from_name(&name) else {
                        return Err(ExprError {
                            column: col,
                            kind: ExprErrorKind::UnknownFunction(name),
                        });
                    };
                    self.pos += 1;
                    let arg = self.expr()?;
                    match self.peek() {
                        Some(Tok::Close) => self.pos += 1,
                        _ => return self.err(ExprErrorKind::ExpectedOperand),
                    }
                    return finite(call(f, arg), col);
                }
                if Func::from_name(&name).is_some() {
                    return Err(ExprError {
                        column: col,
                        kind: ExprErrorKind::MissingArgument(name),
                    });
                }
                match name.as_str() {
                    "u" => Ok(Expr::Var(Var::U)),
                    "v" => Ok(Expr::Var(Var::V)),
                    "t" => Ok(Expr::Var(Var::T)),
                    "pi" => Ok(Expr::Num(std::f64::consts::PI)),
                    _ => match (self.params)(&name) {
                        Some(x) => Ok(Expr::Num(x)),
                        None => Err(ExprError {
                            column: col,
                            kind: ExprErrorKind::UnknownName(name),
                        }),
                    },
                }
            }
            _ => self.err(ExprErrorKind::ExpectedOperand),
        }
    }
}

/// Names that cannot be used for parameters.
pub fn is_reserved_name(name: &str) -> bool {
    matches!(name, "u" | "v" | "t" | "pi") || Func::from_name(name).is_some()
}

impl Expr {
    /// Parses an expression with no parameters.
    pub fn parse(text: &str) -> Result<Expr, ExprError> {
        Self::parse_with(text, &|_| None)
    }

    /// Parses an expression, replacing every other name by `params(name)`.
    pub fn parse_with(text: &str, params: &dyn Fn(&str) -> Option<f64>) -> Result<Expr, ExprError> {
        let toks = lex(text)?;
        if toks.is_empty() {
            return Err(ExprError {
                column: 1,
                kind: ExprErrorKind::Empty,
            });
        }
        let mut p = Parser {
            toks,
            pos: 0,
            end_col: text.chars().count() + 1,
            params,
            nest: 0,
        };
        let e = p.expr()?;
        if p.pos < p.toks.len() {
            return p.err(ExprErrorKind::TrailingInput);
        }
        let depth = e.depth();
        if depth > MAX_DEPTH {
            return Err(ExprError {
                column: 1,
                kind: ExprErrorKind::TooDeepTree { depth },
            });
        }
        Ok(e)
    }

    /// Depth of the tree (a number or variable has depth 1), computed without recursion.
    pub fn depth(&self) -> usize {
        let mut stack = vec![(self, 1usize)];
        let mut max = 0;
        while let Some((e, d)) = stack.pop() {
            max = max.max(d);
            match e {
                Expr::Num(_) | Expr::Var(_) => {}
                Expr::Neg(a) | Expr::Call(_, a) => stack.push((a, d + 1)),
                Expr::Add(a, b)
                | Expr::Sub(a, b)
                | Expr::Mul(a, b)
                | Expr::Div(a, b)
                | Expr::Pow(a, b) => {
                    stack.push((a, d + 1));
                    stack.push((b, d + 1));
                }
            }
        }
        max
    }

    /// Upper bounds of `(size, depth)` of [`Expr::derivative`]`(x)`, and this tree's
    /// `(size, depth)`, in `f64` (they can exceed every integer type), without building it.
    /// The bounds follow the differentiation rules before simplification, which only shrinks.
    fn derivative_bound(&self) -> [f64; 4] {
        // [size, depth, derivative size bound, derivative depth bound]
        let leaf = [1.0, 1.0, 1.0, 1.0];
        match self {
            Expr::Num(_) | Expr::Var(_) => leaf,
            Expr::Neg(a) => {
                let [s, d, ds, dd] = a.derivative_bound();
                [s + 1.0, d + 1.0, ds + 1.0, dd + 1.0]
            }
            Expr::Call(_, a) => {
                let [s, d, ds, dd] = a.derivative_bound();
                [s + 1.0, d + 1.0, ds + s + 5.0, dd.max(d + 3.0) + 1.0]
            }
            Expr::Add(a, b) | Expr::Sub(a, b) => {
                let ([sa, da, dsa, dda], [sb, db, dsb, ddb]) =
                    (a.derivative_bound(), b.derivative_bound());
                [
                    sa + sb + 1.0,
                    da.max(db) + 1.0,
                    dsa + dsb + 1.0,
                    dda.max(ddb) + 1.0,
                ]
            }
            Expr::Mul(a, b) | Expr::Div(a, b) | Expr::Pow(a, b) => {
                let ([sa, da, dsa, dda], [sb, db, dsb, ddb]) =
                    (a.derivative_bound(), b.derivative_bound());
                let size = sa + sb + 1.0;
                let depth = da.max(db) + 1.0;
                // Every rule of a binary node uses each operand's derivative once and the
                // operands (and the node itself for a^b) at most three times, within two new
                // levels for a product (a' b + a b') and four for a quotient or a power.
                let levels = if matches!(self, Expr::Mul(..)) {
                    2.0
                } else {
                    4.0
                };
                [
                    size,
                    depth,
                    dsa + dsb + 3.0 * size + 8.0,
                    dda.max(ddb).max(depth) + levels,
                ]
            }
        }
    }

    /// [`Expr::derivative`] with its size and depth bounded first ([`MAX_DERIVED_NODES`],
    /// [`MAX_DERIVED_DEPTH`]): the error (column 1) says how large it would be.
    pub fn try_derivative(&self, x: Var) -> Result<Expr, ExprError> {
        let [_, _, nodes, depth] = self.derivative_bound();
        if nodes > MAX_DERIVED_NODES || depth > MAX_DERIVED_DEPTH {
            return Err(ExprError {
                column: 1,
                kind: ExprErrorKind::DerivativeTooLarge {
                    var: x.name(),
                    nodes,
                    depth,
                },
            });
        }
        Ok(self.derivative(x))
    }

    /// [`Expr::nth_derivative`] with every step checked as [`Expr::try_derivative`] does.
    pub fn try_nth_derivative(&self, x: Var, k: usize) -> Result<Expr, ExprError> {
        let mut e = self.clone();
        for _ in 0..k {
            e = e.try_derivative(x)?;
        }
        Ok(e)
    }

    /// Evaluates at (u, v, t).
    pub fn eval(&self, u: f64, v: f64, t: f64) -> f64 {
        match self {
            Expr::Num(x) => *x,
            Expr::Var(Var::U) => u,
            Expr::Var(Var::V) => v,
            Expr::Var(Var::T) => t,
            Expr::Neg(a) => -a.eval(u, v, t),
            Expr::Add(a, b) => a.eval(u, v, t) + b.eval(u, v, t),
            Expr::Sub(a, b) => a.eval(u, v, t) - b.eval(u, v, t),
            Expr::Mul(a, b) => a.eval(u, v, t) * b.eval(u, v, t),
            Expr::Div(a, b) => a.eval(u, v, t) / b.eval(u, v, t),
            Expr::Pow(a, b) => {
                let x = a.eval(u, v, t);
                match **b {
                    Expr::Num(n) => num_pow(x, n),
                    _ => x.powf(b.eval(u, v, t)),
                }
            }
            Expr::Call(f, a) => f.apply(a.eval(u, v, t)),
        }
    }

    /// The number, when the expression is a constant.
    pub fn as_number(&self) -> Option<f64> {
        match self {
            Expr::Num(x) => Some(*x),
            _ => None,
        }
    }

    /// Whether the expression depends on `x`.
    pub fn depends_on(&self, x: Var) -> bool {
        match self {
            Expr::Num(_) => false,
            Expr::Var(y) => *y == x,
            Expr::Neg(a) | Expr::Call(_, a) => a.depends_on(x),
            Expr::Add(a, b)
            | Expr::Sub(a, b)
            | Expr::Mul(a, b)
            | Expr::Div(a, b)
            | Expr::Pow(a, b) => a.depends_on(x) || b.depends_on(x),
        }
    }

    /// Exact partial derivative with respect to `x`, simplified. Unbounded: its size can grow
    /// exponentially with the depth (`v^v^...^v`); use [`Expr::try_derivative`] for expressions
    /// that come from a file.
    pub fn derivative(&self, x: Var) -> Expr {
        match self {
            Expr::Num(_) => Expr::Num(0.0),
            Expr::Var(y) => Expr::Num(if *y == x { 1.0 } else { 0.0 }),
            Expr::Neg(a) => neg(a.derivative(x)),
            Expr::Add(a, b) => add(a.derivative(x), b.derivative(x)),
            Expr::Sub(a, b) => sub(a.derivative(x), b.derivative(x)),
            Expr::Mul(a, b) => add(
                mul(a.derivative(x), (**b).clone()),
                mul((**a).clone(), b.derivative(x)),
            ),
            Expr::Div(a, b) => {
                let da = a.derivative(x);
                let db = b.derivative(x);
                sub(
                    div(da, (**b).clone()),
                    div(mul((**a).clone(), db), pow((**b).clone(), Expr::Num(2.0))),
                )
            }
            Expr::Pow(a, b) => {
                let da = a.derivative(x);
                if !b.depends_on(x) {
                    // d(a^b) = b a^(b-1) da
                    let bm1 = sub((**b).clone(), Expr::Num(1.0));
                    mul(mul((**b).clone(), pow((**a).clone(), bm1)), da)
                } else {
                    // d(a^b) = a^b (db ln a + b da / a)
                    let db = b.derivative(x);
                    mul(
                        self.clone(),
                        add(
                            mul(db, call(Func::Ln, (**a).clone())),
                            div(mul((**b).clone(), da), (**a).clone()),
                        ),
                    )
                }
            }
            Expr::Call(f, a) => {
                let da = a.derivative(x);
                let a = (**a).clone();
                let outer = match f {
                    Func::Sin => call(Func::Cos, a),
                    Func::Cos => neg(call(Func::Sin, a)),
                    Func::Tan => div(Expr::Num(1.0), pow(call(Func::Cos, a), Expr::Num(2.0))),
                    Func::Exp => call(Func::Exp, a),
                    Func::Ln => div(Expr::Num(1.0), a),
                    Func::Sqrt => div(Expr::Num(0.5), call(Func::Sqrt, a)),
                    Func::Sinh => call(Func::Cosh, a),
                    Func::Cosh => call(Func::Sinh, a),
                };
                mul(outer, da)
            }
        }
    }

    /// The `k`-th partial derivative with respect to `x`.
    pub fn nth_derivative(&self, x: Var, k: usize) -> Expr {
        let mut e = self.clone();
        for _ in 0..k {
            e = e.derivative(x);
        }
        e
    }

    /// Number of nodes (a measure of evaluation cost), counted without recursion.
    pub fn size(&self) -> usize {
        let mut stack = vec![self];
        let mut n = 0;
        while let Some(e) = stack.pop() {
            n += 1;
            match e {
                Expr::Num(_) | Expr::Var(_) => {}
                Expr::Neg(a) | Expr::Call(_, a) => stack.push(a),
                Expr::Add(a, b)
                | Expr::Sub(a, b)
                | Expr::Mul(a, b)
                | Expr::Div(a, b)
                | Expr::Pow(a, b) => {
                    stack.push(a);
                    stack.push(b);
                }
            }
        }
        n
    }
}

/// `a^b` for numbers: integer exponents through `powi` (exact for negative bases, faster).
#[inline]
fn num_pow(a: f64, b: f64) -> f64 {
    if b.fract() == 0.0 && b.abs() <= 64.0 {
        a.powi(b as i32)
    } else {
        a.powf(b)
    }
}

// Simplifying constructors.

/// `-a`, simplified.
pub fn neg(a: Expr) -> Expr {
    match a {
        Expr::Num(x) => Expr::Num(-x),
        Expr::Neg(b) => *b,
        a => Expr::Neg(Box::new(a)),
    }
}

/// `a + b`, simplified.
#[allow(clippy::redundant_guards)] // guards read better than float patterns
pub fn add(a: Expr, b: Expr) -> Expr {
    match (a, b) {
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(x + y),
        (Expr::Num(x), b) if x == 0.0 => b,
        (a, Expr::Num(y)) if y == 0.0 => a,
        (a, Expr::Neg(b)) => sub(a, *b),
        (a, b) => Expr::Add(Box::new(a), Box::new(b)),
    }
}

/// `a - b`, simplified.
#[allow(clippy::redundant_guards)] // guards read better than float patterns
pub fn sub(a: Expr, b: Expr) -> Expr {
    match (a, b) {
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(x - y),
        (Expr::Num(x), b) if x == 0.0 => neg(b),
        (a, Expr::Num(y)) if y == 0.0 => a,
        (a, Expr::Neg(b)) => add(a, *b),
        (a, b) => Expr::Sub(Box::new(a), Box::new(b)),
    }
}

/// `a * b`, simplified (numbers gathered on the left).
#[allow(clippy::redundant_guards)] // guards read better than float patterns
pub fn mul(a: Expr, b: Expr) -> Expr {
    match (a, b) {
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(x * y),
        (Expr::Num(x), _) | (_, Expr::Num(x)) if x == 0.0 => Expr::Num(0.0),
        (Expr::Num(x), b) if x == 1.0 => b,
        (a, Expr::Num(y)) if y == 1.0 => a,
        (Expr::Num(x), b) if x == -1.0 => neg(b),
        (a, Expr::Num(y)) if y == -1.0 => neg(a),
        (a, Expr::Num(y)) => mul(Expr::Num(y), a),
        (Expr::Num(x), Expr::Mul(b, c)) if matches!(*b, Expr::Num(_)) => {
            let Expr::Num(y) = *b else { unreachable!() };
            mul(Expr::Num(x * y), *c)
        }
        (Expr::Num(x), Expr::Neg(b)) => mul(Expr::Num(-x), *b),
        (Expr::Neg(a), b) => neg(mul(*a, b)),
        (a, Expr::Neg(b)) => neg(mul(a, *b)),
        (a, Expr::Mul(b, c)) if matches!(*b, Expr::Num(_)) => mul(*b, mul(a, *c)),
        (Expr::Mul(a, c), b) if matches!(*a, Expr::Num(_)) => mul(*a, mul(*c, b)),
        (a, b) => Expr::Mul(Box::new(a), Box::new(b)),
    }
}

/// `a / b`, simplified.
#[allow(clippy::redundant_guards)] // guards read better than float patterns
pub fn div(a: Expr, b: Expr) -> Expr {
    match (a, b) {
        // 1/0 and 0/0 fold to inf and NaN, which the parser reports at their column.
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(x / y),
        (Expr::Num(x), _) if x == 0.0 => Expr::Num(0.0),
        (a, Expr::Num(y)) if y == 1.0 => a,
        (a, Expr::Num(y)) if y != 0.0 => mul(Expr::Num(1.0 / y), a),
        (a, b) => Expr::Div(Box::new(a), Box::new(b)),
    }
}

/// `a ^ b`, simplified.
#[allow(clippy::redundant_guards)] // guards read better than float patterns
pub fn pow(a: Expr, b: Expr) -> Expr {
    match (a, b) {
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(num_pow(x, y)),
        (_, Expr::Num(y)) if y == 0.0 => Expr::Num(1.0),
        (a, Expr::Num(y)) if y == 1.0 => a,
        (a, b) => Expr::Pow(Box::new(a), Box::new(b)),
    }
}

/// `f(a)`, folded when `a` is a number.
pub fn call(f: Func, a: Expr) -> Expr {
    match a {
        Expr::Num(x) => Expr::Num(f.apply(x)),
        a => Expr::Call(f, Box::new(a)),
    }
}

fn prec(e: &Expr) -> u8 {
    match e {
        Expr::Add(..) | Expr::Sub(..) => 1,
        Expr::Mul(..) | Expr::Div(..) => 2,
        Expr::Neg(_) => 3,
        Expr::Pow(..) => 4,
        Expr::Num(x) if *x < 0.0 => 3,
        _ => 5,
    }
}

fn fmt_num(x: f64, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    if x == std::f64::consts::PI {
        write!(f, "pi")
    } else {
        write!(f, "{x}")
    }
}

impl fmt::Display for Expr {
    /// Writes the expression so that it parses back to the same tree (parentheses only where
    /// needed).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let wrap = |e: &Expr, min: u8, f: &mut fmt::Formatter<'_>| -> fmt::Result {
            if prec(e) < min {
                write!(f, "({e})")
            } else {
                write!(f, "{e}")
            }
        };
        match self {
            Expr::Num(x) => fmt_num(*x, f),
            Expr::Var(x) => write!(f, "{}", x.name()),
            Expr::Neg(a) => {
                write!(f, "-")?;
                wrap(a, 4, f)
            }
            Expr::Add(a, b) => {
                wrap(a, 1, f)?;
                write!(f, " + ")?;
                wrap(b, 2, f)
            }
            Expr::Sub(a, b) => {
                wrap(a, 1, f)?;
                write!(f, " - ")?;
                wrap(b, 2, f)
            }
            Expr::Mul(a, b) => {
                wrap(a, 2, f)?;
                write!(f, "*")?;
                wrap(b, 4, f)
            }
            Expr::Div(a, b) => {
                wrap(a, 2, f)?;
                write!(f, "/")?;
                wrap(b, 4, f)
            }
            Expr::Pow(a, b) => {
                wrap(a, 5, f)?;
                write!(f, "^")?;
                wrap(b, 4, f)
            }
            Expr::Call(g, a) => write!(f, "{}({a})", g.name()),
        }
    }
}
