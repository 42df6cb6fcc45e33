//! CSG expressions over numbered solids, and where along a grid edge
//! their value changes. The robust reconstruction ([`crate::robust`])
//! evaluates an [`Expr`] on every node's operand states (64 nodes at a time)
//! and places each result vertex with [`result_vertex`]; booleans are the
//! two-operand case.

crate::choice! {
    /// A boolean operator of [`Expr`].
    pub enum BoolOp {
        /// Inside any child.
        Union => "union",
        /// Inside every child.
        Intersection => "intersection",
        /// Inside the first child and no other.
        Difference => "difference",
    }
}

/// A CSG expression over numbered operands (n-ary, nesting).
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    Operand(usize),
    Op(BoolOp, Vec<Expr>),
}

impl Expr {
    /// The expression's value for the operands' inside/outside states.
    pub fn eval(&self, inside: &[bool]) -> bool {
        match self {
            Expr::Operand(i) => inside[*i],
            Expr::Op(BoolOp::Union, c) => c.iter().any(|e| e.eval(inside)),
            Expr::Op(BoolOp::Intersection, c) => c.iter().all(|e| e.eval(inside)),
            Expr::Op(BoolOp::Difference, c) => c.first().is_some_and(|e| e.eval(inside)) && !c[1..].iter().any(|e| e.eval(inside)),
        }
    }
    /// The same, 64 nodes at a time on state bitmaps.
    pub(crate) fn eval_words(&self, words: &[u64]) -> u64 {
        match self {
            Expr::Operand(i) => words[*i],
            Expr::Op(BoolOp::Union, c) => c.iter().fold(0, |a, e| a | e.eval_words(words)),
            Expr::Op(BoolOp::Intersection, c) => c.iter().fold(!0, |a, e| a & e.eval_words(words)),
            Expr::Op(BoolOp::Difference, c) => {
                let first = c.first().map_or(0, |e| e.eval_words(words));
                c[1..].iter().fold(first, |a, e| a & !e.eval_words(words))
            }
        }
    }
    /// The largest operand number used, plus one.
    pub fn operands(&self) -> usize {
        match self {
            Expr::Operand(i) => i + 1,
            Expr::Op(_, c) => c.iter().map(Expr::operands).max().unwrap_or(0),
        }
    }
}

/// Where along an edge the result changes, given each operand's vertex on
/// that edge (operands whose state does not change have none): walk the
/// operands' vertices in order, flipping each operand's state, and stop at
/// the first flip that changes the expression. With one operand this is
/// that operand's vertex; for A ∪ A it is A's vertex again. Returns the
/// vertex and the operand it came from.
pub(crate) fn result_vertex(expr: &Expr, lower: &mut [bool], changes: &mut [(f64, usize)]) -> Option<(f64, usize)> {
    changes.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut r = expr.eval(lower);
    for &(v, o) in changes.iter() {
        lower[o] = !lower[o];
        let r2 = expr.eval(lower);
        if r2 != r {
            return Some((v, o));
        }
        r = r2;
    }
    None
}
