//! Forward-mode derivatives of a recorded function of the state (a
//! right-hand side, or a model's signals), as a tape of their own: from the
//! tape of `f(x)` ([`super::tape`]), the tape of `f(x)` together with
//! `(df/dx) s_j` for `p` directions `s_j` read from the state vector after
//! `x` (the layout of a forward-sensitivity system: `x`, then `s_1`, ...,
//! `s_p`, `n` entries each), stored the same way after `f` (`m` entries each).
//!
//! Each recorded operation gets its value node (the same operation on the
//! same operands, so `f` comes out as the recorded evaluation's numbers) and
//! per direction a tangent node from the operation's derivative rule, the
//! local derivative computed once and shared by the directions. A tangent
//! known to be zero (a constant's, an input's, one multiplied by a zero) is
//! not recorded at all. The guards are the recorded ones: a branch taken
//! another way gives up for the value and its derivatives alike.
//!
//! `|a|` has the kink's zero slope at `a = 0` ([`Node::Sign`]), as the
//! physics' [`fistage_model::Scalar::kink_abs`] has in dual numbers; the
//! rounding functions have slope zero. Functions whose derivative would need
//! a branch the tape does not hold (`max`, `min` and `rem` of two moving
//! values, `powf` and `log` in a moving exponent or base) are refused.

use std::collections::HashMap;

use super::calls::{Call1, Call2};
use super::tape::{Guard, Node, NodeId, NodeKey, Output, Slot, Tape, key_of};

/// A tangent: `None` is a derivative known to be zero.
type Tangent = Option<NodeId>;

/// Per node of a tape, the directions its constant moves along and by how
/// much (empty for a plain state derivative).
pub(crate) type Seeds = HashMap<NodeId, Vec<(usize, f64)>>;

/// The tape of `f` and its derivatives along `directions` state directions;
/// `n` is the number of states, `m` the number of `f`'s outputs (entries
/// of the output array: a right-hand side's `n`, or a model's signals).
///
/// `seeds` gives constants a derivative of their own: entry `i` lists
/// `(j, d)` where the constant of node `i` moves by `d` along direction `j`
/// (a model number that depends on a parameter, see
/// [`super::sensitivity::parametric_kernel`]); the tangent of direction `j`
/// is then `(df/dx) s_j + df/dtheta_j`.
pub(crate) fn tangent_tape(
    tape: &Tape,
    n: usize,
    m: usize,
    directions: usize,
    seeds: &Seeds,
) -> Result<Tape, String> {
    let mut builder = Builder::default();
    let mut values: Vec<NodeId> = Vec::with_capacity(tape.nodes.len());
    let mut tangents: Vec<Vec<Tangent>> = Vec::with_capacity(tape.nodes.len());
    let mut guards = tape.guards.iter().peekable();
    for (i, node) in tape.nodes.iter().enumerate() {
        while let Some((_, guard)) = guards.next_if(|(at, _)| *at <= values.len()) {
            builder.guard(guard, &values);
        }
        let value = builder.push(remap(node, &values));
        let tangent = match seeds.get(&(i as NodeId)) {
            Some(moves) => {
                let mut tangent = vec![None; directions];
                for &(j, d) in moves.iter().filter(|(j, _)| *j < directions) {
                    tangent[j] = Some(builder.constant(d));
                }
                tangent
            }
            None => builder.derivative(node, value, &values, &tangents, n, directions)?,
        };
        values.push(value);
        tangents.push(tangent);
    }
    for (_, guard) in guards {
        builder.guard(guard, &values);
    }
    let zero = builder.constant(0.0);
    let mut outputs = Vec::with_capacity(tape.outputs.len() * (1 + directions));
    for &(output, node) in &tape.outputs {
        let Output::Derivative(c) = output else {
            return Err("only a function of the state has a tangent".into());
        };
        if c as usize >= m {
            return Err(format!("output {c} lies beyond the {m} outputs"));
        }
        outputs.push((output, values[node as usize]));
        for (j, tangent) in tangents[node as usize].iter().enumerate() {
            let at = slot_index(m, j, c as usize)?;
            outputs.push((Output::Derivative(at), tangent.unwrap_or(zero)));
        }
    }
    builder.tape.outputs = outputs;
    Ok(builder.tape)
}

/// Entry `c` of direction `j` in the sensitivity layout of `n` entries.
fn slot_index(n: usize, j: usize, c: usize) -> Result<u32, String> {
    u32::try_from(n * (1 + j) + c).map_err(|_| "too many directions".to_string())
}

/// `node` with its operands moved to their new places.
fn remap(node: &Node, values: &[NodeId]) -> Node {
    let at = |id: NodeId| values[id as usize];
    match *node {
        Node::Const(c) => Node::Const(c),
        Node::Input(slot) => Node::Input(slot),
        Node::Neg(a) => Node::Neg(at(a)),
        Node::Abs(a) => Node::Abs(at(a)),
        Node::Sqrt(a) => Node::Sqrt(at(a)),
        Node::Add(a, b) => Node::Add(at(a), at(b)),
        Node::Sub(a, b) => Node::Sub(at(a), at(b)),
        Node::Mul(a, b) => Node::Mul(at(a), at(b)),
        Node::Div(a, b) => Node::Div(at(a), at(b)),
        Node::Call1(f, a) => Node::Call1(f, at(a)),
        Node::Call2(f, a, b) => Node::Call2(f, at(a), at(b)),
        Node::Sign(a) => Node::Sign(at(a)),
    }
}

/// The new tape, with identical nodes kept once and the identities of
/// zero and one applied (tangents are mostly sums of products).
#[derive(Default)]
struct Builder {
    tape: Tape,
    known: HashMap<NodeKey, NodeId>,
}

impl Builder {
    fn push(&mut self, node: Node) -> NodeId {
        let key = key_of(&node);
        if let Some(&id) = self.known.get(&key) {
            return id;
        }
        let id = self.tape.nodes.len() as NodeId;
        self.tape.nodes.push(node);
        self.known.insert(key, id);
        id
    }

    fn guard(&mut self, guard: &Guard, values: &[NodeId]) {
        let at = self.tape.nodes.len();
        self.tape.guards.push((
            at,
            Guard {
                a: values[guard.a as usize],
                b: values[guard.b as usize],
                holds: guard.holds,
            },
        ));
    }

    fn constant(&mut self, c: f64) -> NodeId {
        self.push(Node::Const(c))
    }

    fn constant_of(&self, id: NodeId) -> Option<f64> {
        match self.tape.nodes[id as usize] {
            Node::Const(c) => Some(c),
            _ => None,
        }
    }

    fn mul(&mut self, a: NodeId, b: NodeId) -> Tangent {
        match (self.constant_of(a), self.constant_of(b)) {
            (Some(0.0), _) | (_, Some(0.0)) => None,
            (Some(1.0), _) => Some(b),
            (_, Some(1.0)) => Some(a),
            _ => Some(self.push(Node::Mul(a, b))),
        }
    }

    fn add(&mut self, a: Tangent, b: Tangent) -> Tangent {
        match (a, b) {
            (Some(a), Some(b)) => Some(self.push(Node::Add(a, b))),
            (a, None) => a,
            (None, b) => b,
        }
    }

    fn sub(&mut self, a: Tangent, b: Tangent) -> Tangent {
        match (a, b) {
            (Some(a), Some(b)) => Some(self.push(Node::Sub(a, b))),
            (a, None) => a,
            (None, Some(b)) => Some(self.push(Node::Neg(b))),
        }
    }

    /// `t * by`.
    fn scale(&mut self, t: Tangent, by: NodeId) -> Tangent {
        t.and_then(|t| self.mul(t, by))
    }

    /// Every direction's tangent scaled by the local derivative `local`
    /// (made only when some direction moves).
    fn chain(&mut self, ta: &[Tangent], local: impl FnOnce(&mut Self) -> NodeId) -> Vec<Tangent> {
        if ta.iter().all(Option::is_none) {
            return ta.to_vec();
        }
        let d = local(self);
        ta.iter().map(|&t| self.scale(t, d)).collect()
    }

    fn call1(&mut self, f: Call1, a: NodeId) -> NodeId {
        self.push(Node::Call1(f, a))
    }

    fn div(&mut self, a: NodeId, b: NodeId) -> NodeId {
        self.push(Node::Div(a, b))
    }

    fn times(&mut self, a: NodeId, b: NodeId) -> NodeId {
        self.push(Node::Mul(a, b))
    }

    /// `1 / g` for a local derivative `1 / g(a)`.
    fn reciprocal(&mut self, g: NodeId) -> NodeId {
        let one = self.constant(1.0);
        self.div(one, g)
    }

    /// The tangents of `node` (recorded as `value`) in every direction.
    fn derivative(
        &mut self,
        node: &Node,
        value: NodeId,
        values: &[NodeId],
        tangents: &[Vec<Tangent>],
        n: usize,
        directions: usize,
    ) -> Result<Vec<Tangent>, String> {
        let v = |id: NodeId| values[id as usize];
        let t = |id: NodeId| tangents[id as usize].as_slice();
        Ok(match *node {
            Node::Const(_) | Node::Input(Slot::Input(_) | Slot::Step) => vec![None; directions],
            Node::Input(Slot::State(k)) if (k as usize) < n => (0..directions)
                .map(|j| {
                    let at = slot_index(n, j, k as usize)?;
                    Ok(Some(self.push(Node::Input(Slot::State(at)))))
                })
                .collect::<Result<_, String>>()?,
            Node::Input(Slot::State(k)) => {
                return Err(format!("state entry {k} lies beyond the {n} states"));
            }
            Node::Neg(a) => t(a).iter().map(|&ta| self.sub(None, ta)).collect(),
            Node::Abs(a) => self.chain(t(a), |b| b.push(Node::Sign(v(a)))),
            Node::Sign(_) => vec![None; directions],
            Node::Sqrt(a) => self.chain(t(a), |b| {
                let half = b.constant(0.5);
                b.div(half, value)
            }),
            Node::Add(a, b) => (0..directions)
                .map(|j| self.add(t(a)[j], t(b)[j]))
                .collect(),
            Node::Sub(a, b) => (0..directions)
                .map(|j| self.sub(t(a)[j], t(b)[j]))
                .collect(),
            Node::Mul(a, b) => (0..directions)
                .map(|j| {
                    let left = self.scale(t(a)[j], v(b));
                    let right = self.scale(t(b)[j], v(a));
                    self.add(left, right)
                })
                .collect(),
            // (ta - q tb) / b with q = a / b.
            Node::Div(a, b) => (0..directions)
                .map(|j| {
                    let moved = self.scale(t(b)[j], value);
                    let numerator = self.sub(t(a)[j], moved);
                    numerator.map(|num| self.div(num, v(b)))
                })
                .collect(),
            Node::Call1(f, a) => self.call1_rule(f, v(a), value, t(a)),
            Node::Call2(f, a, b) => self.call2_rule(f, (v(a), v(b)), value, (t(a), t(b)))?,
        })
    }

    fn call1_rule(&mut self, f: Call1, a: NodeId, value: NodeId, ta: &[Tangent]) -> Vec<Tangent> {
        use Call1::*;
        let square = |b: &mut Self, x: NodeId| b.times(x, x);
        self.chain(ta, |b| match f {
            Exp => value,
            Exp2 => {
                let ln2 = b.constant(std::f64::consts::LN_2);
                b.times(value, ln2)
            }
            ExpM1 => {
                let one = b.constant(1.0);
                b.push(Node::Add(value, one))
            }
            Ln => b.reciprocal(a),
            Ln1p => {
                let one = b.constant(1.0);
                let g = b.push(Node::Add(one, a));
                b.reciprocal(g)
            }
            Log2 | Log10 => {
                let base = if f == Log2 {
                    std::f64::consts::LN_2
                } else {
                    std::f64::consts::LN_10
                };
                let ln_base = b.constant(base);
                let g = b.times(a, ln_base);
                b.reciprocal(g)
            }
            Cbrt => {
                let three = b.constant(3.0);
                let g = b.times(three, a);
                b.div(value, g)
            }
            Sin => b.call1(Cos, a),
            Cos => {
                let s = b.call1(Sin, a);
                b.push(Node::Neg(s))
            }
            Tan => {
                let one = b.constant(1.0);
                let v2 = square(b, value);
                b.push(Node::Add(one, v2))
            }
            Asin | Acos => {
                let one = b.constant(1.0);
                let a2 = square(b, a);
                let g = b.push(Node::Sub(one, a2));
                let root = b.push(Node::Sqrt(g));
                let d = b.reciprocal(root);
                if f == Acos { b.push(Node::Neg(d)) } else { d }
            }
            Atan => {
                let one = b.constant(1.0);
                let a2 = square(b, a);
                let g = b.push(Node::Add(one, a2));
                b.reciprocal(g)
            }
            Sinh => b.call1(Cosh, a),
            Cosh => b.call1(Sinh, a),
            Tanh => {
                let one = b.constant(1.0);
                let v2 = square(b, value);
                b.push(Node::Sub(one, v2))
            }
            Asinh | Acosh => {
                let one = b.constant(1.0);
                let a2 = square(b, a);
                let g = if f == Asinh {
                    b.push(Node::Add(a2, one))
                } else {
                    b.push(Node::Sub(a2, one))
                };
                let root = b.push(Node::Sqrt(g));
                b.reciprocal(root)
            }
            Atanh => {
                let one = b.constant(1.0);
                let a2 = square(b, a);
                let g = b.push(Node::Sub(one, a2));
                b.reciprocal(g)
            }
            Floor | Ceil | Round | Trunc | Signum => b.constant(0.0),
            Fract => b.constant(1.0),
            Powi(0) => b.constant(0.0),
            Powi(1) => b.constant(1.0),
            Powi(k) => {
                let lower = b.call1(Powi(k - 1), a);
                let k = b.constant(k as f64);
                b.times(k, lower)
            }
        })
    }

    fn call2_rule(
        &mut self,
        f: Call2,
        (a, b): (NodeId, NodeId),
        value: NodeId,
        (ta, tb): (&[Tangent], &[Tangent]),
    ) -> Result<Vec<Tangent>, String> {
        let b_moves = tb.iter().any(Option::is_some);
        if !b_moves && ta.iter().all(Option::is_none) {
            return Ok(ta.to_vec());
        }
        let refuse = |what: &str| Err(format!("the derivative of {what} is not compiled"));
        Ok(match f {
            // d atan2(a, b) = (b da - a db) / (a^2 + b^2).
            Call2::Atan2 => {
                let (a2, b2) = (self.times(a, a), self.times(b, b));
                let h = self.push(Node::Add(a2, b2));
                let (ca, cb) = (self.div(b, h), self.div(a, h));
                (0..ta.len())
                    .map(|j| {
                        let left = self.scale(ta[j], ca);
                        let right = self.scale(tb[j], cb);
                        self.sub(left, right)
                    })
                    .collect()
            }
            Call2::Hypot => {
                let (ca, cb) = (self.div(a, value), self.div(b, value));
                (0..ta.len())
                    .map(|j| {
                        let left = self.scale(ta[j], ca);
                        let right = self.scale(tb[j], cb);
                        self.add(left, right)
                    })
                    .collect()
            }
            Call2::Powf if !b_moves => self.chain(ta, |s| {
                let one = s.constant(1.0);
                let lower_exponent = s.push(Node::Sub(b, one));
                let lower = s.push(Node::Call2(Call2::Powf, a, lower_exponent));
                s.times(b, lower)
            }),
            Call2::Log if !b_moves => self.chain(ta, |s| {
                let ln_base = s.call1(Call1::Ln, b);
                let g = s.times(a, ln_base);
                s.reciprocal(g)
            }),
            // copysign(a, b) = |a| sgn(b), with the sign of a zero b kept.
            Call2::Copysign => self.chain(ta, |s| {
                let sa = s.push(Node::Sign(a));
                let one = s.constant(1.0);
                let sb = s.push(Node::Call2(Call2::Copysign, one, b));
                s.times(sa, sb)
            }),
            Call2::Rem if !b_moves => ta.to_vec(),
            Call2::Powf => return refuse("powf in a moving exponent"),
            Call2::Log => return refuse("log in a moving base"),
            Call2::Max => return refuse("max of moving values"),
            Call2::Min => return refuse("min of moving values"),
            Call2::Rem => return refuse("rem by a moving divisor"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::tape::sign;
    use super::*;

    /// The tangent tape of a small function agrees with its derivative
    /// worked out by hand, and gives the function's own values.
    #[test]
    fn the_tangent_of_a_small_tape_is_its_derivative() {
        // f0 = exp(-(x1/x0)^2) * |x1| + sqrt(x0), f1 = atan2(x1, x0).
        let mut tape = Tape::default();
        let nodes = &mut tape.nodes;
        nodes.push(Node::Input(Slot::State(0))); // 0
        nodes.push(Node::Input(Slot::State(1))); // 1
        nodes.push(Node::Div(1, 0)); // 2
        nodes.push(Node::Call1(Call1::Powi(2), 2)); // 3
        nodes.push(Node::Neg(3)); // 4
        nodes.push(Node::Call1(Call1::Exp, 4)); // 5
        nodes.push(Node::Abs(1)); // 6
        nodes.push(Node::Mul(5, 6)); // 7
        nodes.push(Node::Sqrt(0)); // 8
        nodes.push(Node::Add(7, 8)); // 9
        nodes.push(Node::Call2(Call2::Atan2, 1, 0)); // 10
        tape.outputs = vec![(Output::Derivative(0), 9), (Output::Derivative(1), 10)];
        let tangent = tangent_tape(&tape, 2, 2, 2, &Seeds::new()).expect("differentiable");
        let f = |x0: f64, x1: f64| {
            [
                (-(x1 / x0).powi(2)).exp() * x1.abs() + x0.sqrt(),
                x1.atan2(x0),
            ]
        };
        let x = [1.3, -0.4];
        let s = [[0.2, 0.7], [-1.1, 0.05]];
        let mut y = x.to_vec();
        y.extend(s.iter().flatten());
        let got = tangent.evaluate(&y, &[], 0.0).expect("no guards");
        let order: Vec<u32> = tangent
            .outputs
            .iter()
            .map(|(o, _)| match o {
                Output::Derivative(k) => *k,
                Output::State(_) => u32::MAX,
            })
            .collect();
        let mut dy = [0.0; 6];
        for (k, value) in order.iter().zip(&got) {
            dy[*k as usize] = *value;
        }
        assert_eq!(&dy[..2], &f(x[0], x[1]));
        let h = 1e-6;
        for (j, dir) in s.iter().enumerate() {
            let up = f(x[0] + h * dir[0], x[1] + h * dir[1]);
            let down = f(x[0] - h * dir[0], x[1] - h * dir[1]);
            for c in 0..2 {
                let difference = (up[c] - down[c]) / (2.0 * h);
                let exact = dy[2 * (1 + j) + c];
                assert!(
                    (exact - difference).abs() < 1e-8,
                    "direction {j} output {c}: {exact} against {difference}"
                );
            }
        }
        assert_eq!(sign(0.0), 0.0);
        assert_eq!(sign(-2.0), -1.0);
    }

    /// A derivative that needs a branch the tape does not hold is refused.
    #[test]
    fn max_of_two_moving_values_is_refused() {
        let mut tape = Tape::default();
        tape.nodes.push(Node::Input(Slot::State(0)));
        tape.nodes.push(Node::Input(Slot::State(1)));
        tape.nodes.push(Node::Call2(Call2::Max, 0, 1));
        tape.outputs = vec![(Output::Derivative(0), 2)];
        let refused = tangent_tape(&tape, 2, 1, 1, &Seeds::new()).expect_err("refused");
        assert!(refused.contains("max"), "{refused}");
    }
}
