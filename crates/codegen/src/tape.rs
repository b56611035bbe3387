//! The record of one traced evaluation: every floating-point operation the
//! generic evaluation performed on the traced inputs, in order, as a tape of
//! [`Node`]s, with the comparisons it branched on as [`Guard`]s and the values
//! it wrote as outputs.
//!
//! The recorder simplifies as it records, and only where the result is the
//! same number: operations on constants are carried out at once (the same
//! IEEE operation the evaluation would perform at run time), a repeated
//! operation on the same operands is recorded once, and the identities
//! `x * 1`, `x / 1`, `x + 0`, `x - 0` and products with a zero coefficient
//! are dropped. The last two differ from the evaluation only in the sign of
//! a zero result or when an operand is not finite, which an integrator
//! rejects anyway.
//!
//! One tape is recorded at a time per thread ([`record`]); a traced value
//! used outside its recording marks the recording unusable instead of
//! panicking.

use std::cell::RefCell;
use std::collections::HashMap;

use super::calls::{Call1, Call2};

/// Index of a node on the tape.
pub(crate) type NodeId = u32;

/// One recorded value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Node {
    /// A constant.
    Const(f64),
    /// An input of the compiled function ([`Slot`]).
    Input(Slot),
    /// `-a`.
    Neg(NodeId),
    /// `|a|`.
    Abs(NodeId),
    /// `sqrt(a)` (correctly rounded, as `f64::sqrt`).
    Sqrt(NodeId),
    /// `a + b`.
    Add(NodeId, NodeId),
    /// `a - b`.
    Sub(NodeId, NodeId),
    /// `a * b`.
    Mul(NodeId, NodeId),
    /// `a / b`.
    Div(NodeId, NodeId),
    /// A one-argument library function.
    Call1(Call1, NodeId),
    /// A two-argument library function.
    Call2(Call2, NodeId, NodeId),
    /// The sign of `a` with zero at zero: -1, 0 or 1 (the derivative of
    /// `|a|` with the kink's zero slope, as [`fistage_model::Scalar::kink_abs`];
    /// made by the tangent transformation, never recorded).
    Sign(NodeId),
}

/// Where an input of the compiled function is read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Slot {
    /// Entry of the state vector.
    State(u32),
    /// Entry of the input vector (the fields of `InputValues` in order).
    Input(u32),
    /// The implicit stage's step (implicit kernels only).
    Step,
}

/// A comparison the evaluation branched on: at run time `a cmp b` must come
/// out as it did when recorded, or the compiled function gives up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Guard {
    /// Left operand.
    pub a: NodeId,
    /// Right operand.
    pub b: NodeId,
    /// What must hold.
    pub holds: Holds,
}

/// The outcome a guard requires of `a` against `b`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Holds {
    /// `a == b`.
    Equal,
    /// `a != b` (unequal or unordered).
    NotEqual,
    /// `a < b`.
    Less,
    /// `a > b`.
    Greater,
    /// Unordered (either is NaN).
    Unordered,
}

impl Holds {
    /// Whether `a` against `b` comes out this way.
    #[cfg(test)]
    pub(crate) fn of(self, a: f64, b: f64) -> bool {
        match self {
            Self::Equal => a == b,
            Self::NotEqual => a != b,
            Self::Less => a < b,
            Self::Greater => a > b,
            Self::Unordered => a.is_nan() || b.is_nan(),
        }
    }

    /// The outcome `a` against `b` has: one of equal, less, greater or
    /// unordered.
    pub(crate) fn ordering(a: f64, b: f64) -> Self {
        match a.partial_cmp(&b) {
            Some(std::cmp::Ordering::Equal) => Self::Equal,
            Some(std::cmp::Ordering::Less) => Self::Less,
            Some(std::cmp::Ordering::Greater) => Self::Greater,
            None => Self::Unordered,
        }
    }
}

/// A finished recording.
#[derive(Debug, Clone, Default)]
pub(crate) struct Tape {
    /// The nodes, each after its operands.
    pub nodes: Vec<Node>,
    /// Guards, each with the number of nodes recorded before it.
    pub guards: Vec<(usize, Guard)>,
    /// Outputs: (where to store, the value).
    pub outputs: Vec<(Output, NodeId)>,
}

/// Where the compiled function stores an output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Output {
    /// Entry of the state derivative.
    Derivative(u32),
    /// Entry of the state vector (an implicit stage's solved bristle state).
    State(u32),
}

impl Tape {
    /// Which nodes the outputs and guards need.
    pub(crate) fn live(&self) -> Vec<bool> {
        let mut live = vec![false; self.nodes.len()];
        for &(_, node) in &self.outputs {
            live[node as usize] = true;
        }
        for (_, guard) in &self.guards {
            live[guard.a as usize] = true;
            live[guard.b as usize] = true;
        }
        for i in (0..self.nodes.len()).rev() {
            if live[i] {
                for operand in operands(&self.nodes[i]) {
                    live[operand as usize] = true;
                }
            }
        }
        live
    }

    /// The order to compute the live nodes in: each library call as early
    /// as its operands allow (with only those operands computed before it),
    /// then everything else in recorded order. A call clobbers every
    /// floating-point register, so values computed before it must be kept
    /// in memory across it; calls first keeps that to the calls' own
    /// results. The operations are pure, so the order changes no number.
    pub(crate) fn schedule(&self) -> Vec<usize> {
        let live = self.live();
        let mut done = vec![false; self.nodes.len()];
        let mut order = Vec::with_capacity(self.nodes.len());
        let mut stack = Vec::new();
        let calls = (0..self.nodes.len())
            .filter(|&i| live[i] && matches!(self.nodes[i], Node::Call1(..) | Node::Call2(..)));
        for call in calls {
            // Post-order walk of the call's operands (each after its own).
            stack.push((call, false));
            while let Some((i, expanded)) = stack.pop() {
                if done[i] {
                    continue;
                }
                if expanded {
                    done[i] = true;
                    order.push(i);
                } else {
                    stack.push((i, true));
                    for operand in operands(&self.nodes[i]) {
                        if !done[operand as usize] {
                            stack.push((operand as usize, false));
                        }
                    }
                }
            }
        }
        order.extend((0..self.nodes.len()).filter(|&i| live[i] && !done[i]));
        order
    }

    /// Number of live operations (constants and inputs not counted).
    pub(crate) fn operations(&self) -> usize {
        let live = self.live();
        self.nodes
            .iter()
            .zip(&live)
            .filter(|(node, live)| **live && !matches!(node, Node::Const(_) | Node::Input(_)))
            .count()
    }

    /// The tape evaluated in Rust: the outputs at `state`, `inputs` and
    /// `step` in the order of [`Tape::outputs`], or `None` when a guard fails.
    #[cfg(test)]
    pub(crate) fn evaluate(&self, state: &[f64], inputs: &[f64], step: f64) -> Option<Vec<f64>> {
        let mut values = Vec::with_capacity(self.nodes.len());
        let mut guards = self.guards.iter().peekable();
        for (i, node) in self.nodes.iter().enumerate() {
            while let Some((_, guard)) = guards.next_if(|(at, _)| *at <= i) {
                if !guard
                    .holds
                    .of(values[guard.a as usize], values[guard.b as usize])
                {
                    return None;
                }
            }
            let at = |id: NodeId| values[id as usize];
            let value = match *node {
                Node::Const(c) => c,
                Node::Input(Slot::State(k)) => state[k as usize],
                Node::Input(Slot::Input(k)) => inputs[k as usize],
                Node::Input(Slot::Step) => step,
                Node::Neg(a) => -at(a),
                Node::Abs(a) => at(a).abs(),
                Node::Sqrt(a) => at(a).sqrt(),
                Node::Add(a, b) => at(a) + at(b),
                Node::Sub(a, b) => at(a) - at(b),
                Node::Mul(a, b) => at(a) * at(b),
                Node::Div(a, b) => at(a) / at(b),
                Node::Call1(f, a) => f.apply(at(a)),
                Node::Call2(f, a, b) => f.apply(at(a), at(b)),
                Node::Sign(a) => sign(at(a)),
            };
            values.push(value);
        }
        for (_, guard) in guards {
            if !guard
                .holds
                .of(values[guard.a as usize], values[guard.b as usize])
            {
                return None;
            }
        }
        Some(
            self.outputs
                .iter()
                .map(|&(_, n)| values[n as usize])
                .collect(),
        )
    }
}

/// The operands of a node.
pub(crate) fn operands(node: &Node) -> impl Iterator<Item = NodeId> {
    let (a, b) = match *node {
        Node::Const(_) | Node::Input(_) => (None, None),
        Node::Neg(a) | Node::Abs(a) | Node::Sqrt(a) | Node::Call1(_, a) | Node::Sign(a) => {
            (Some(a), None)
        }
        Node::Add(a, b)
        | Node::Sub(a, b)
        | Node::Mul(a, b)
        | Node::Div(a, b)
        | Node::Call2(_, a, b) => (Some(a), Some(b)),
    };
    a.into_iter().chain(b)
}

/// The recording in progress on this thread.
struct Recorder {
    tape: Tape,
    /// The value each node had in the recorded evaluation.
    values: Vec<f64>,
    /// Nodes already recorded, for reuse (constants by their bits).
    known: HashMap<NodeKey, NodeId>,
    /// Why the recording cannot be compiled, if it cannot.
    unusable: Option<String>,
}

/// The sign of `a` with zero at zero ([`Node::Sign`]).
#[cfg(test)]
pub(crate) fn sign(a: f64) -> f64 {
    if a == 0.0 { 0.0 } else { 1f64.copysign(a) }
}

/// A node as a hash key (constants by their bit pattern).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum NodeKey {
    Const(u64),
    Input(Slot),
    Op(u8, u32, NodeId, NodeId),
}

pub(crate) fn key_of(node: &Node) -> NodeKey {
    let op = |tag: u8, a: NodeId, b: NodeId| NodeKey::Op(tag, 0, a, b);
    match *node {
        Node::Const(c) => NodeKey::Const(c.to_bits()),
        Node::Input(slot) => NodeKey::Input(slot),
        Node::Neg(a) => op(0, a, 0),
        Node::Abs(a) => op(1, a, 0),
        Node::Sqrt(a) => op(2, a, 0),
        Node::Add(a, b) => op(3, a, b),
        Node::Sub(a, b) => op(4, a, b),
        Node::Mul(a, b) => op(5, a, b),
        Node::Div(a, b) => op(6, a, b),
        Node::Call1(f, a) => NodeKey::Op(7, f.code(), a, 0),
        Node::Call2(f, a, b) => NodeKey::Op(8, f.code(), a, b),
        Node::Sign(a) => op(9, a, 0),
    }
}

thread_local! {
    static RECORDER: RefCell<Option<Recorder>> = const { RefCell::new(None) };
}

/// Records what `evaluate` does on traced values; `evaluate` returns the
/// outputs to store. The tape, or why it cannot be compiled.
pub(crate) fn record(evaluate: impl FnOnce() -> Vec<(Output, NodeId)>) -> Result<Tape, String> {
    let previous = RECORDER.with(|r| {
        r.borrow_mut().replace(Recorder {
            tape: Tape::default(),
            values: Vec::new(),
            known: HashMap::new(),
            unusable: None,
        })
    });
    let outputs = evaluate();
    let recorder = RECORDER.with(|r| std::mem::replace(&mut *r.borrow_mut(), previous));
    let Some(mut recorder) = recorder else {
        return Err("the recording was lost".into());
    };
    if let Some(why) = recorder.unusable {
        return Err(why);
    }
    recorder.tape.outputs = outputs;
    Ok(recorder.tape)
}

/// Runs `f` on the recording of this thread, if one is in progress.
fn with_recorder<R>(f: impl FnOnce(&mut Recorder) -> R) -> Option<R> {
    RECORDER.with(|r| r.borrow_mut().as_mut().map(f))
}

/// A node id standing for "no recording": values made outside a recording.
pub(crate) const DETACHED: NodeId = NodeId::MAX;

/// Marks the recording in progress unusable, with the reason (the first
/// reason is kept).
pub(crate) fn mark_unusable(why: impl FnOnce() -> String) {
    with_recorder(|r| {
        if r.unusable.is_none() {
            r.unusable = Some(why());
        }
    });
}

/// Records `node` with its value in the recorded evaluation; the node to use
/// (a simpler equivalent one, or an earlier identical one).
pub(crate) fn push(node: Node, value: f64) -> NodeId {
    with_recorder(|r| r.push(node, value)).unwrap_or(DETACHED)
}

/// Records a guard.
pub(crate) fn guard(a: NodeId, b: NodeId, holds: Holds) {
    with_recorder(|r| {
        if a == DETACHED || b == DETACHED {
            r.unusable
                .get_or_insert_with(|| "a value from outside the recording".into());
            return;
        }
        // A comparison of constants needs no guard.
        if let (Node::Const(_), Node::Const(_)) =
            (r.tape.nodes[a as usize], r.tape.nodes[b as usize])
        {
            return;
        }
        let at = r.tape.nodes.len();
        r.tape.guards.push((at, Guard { a, b, holds }));
    });
}

impl Recorder {
    fn constant(&self, id: NodeId) -> Option<f64> {
        match self.tape.nodes[id as usize] {
            Node::Const(c) => Some(c),
            _ => None,
        }
    }

    fn push(&mut self, node: Node, value: f64) -> NodeId {
        if operands(&node).any(|o| o == DETACHED) {
            self.unusable
                .get_or_insert_with(|| "a value from outside the recording".into());
            return DETACHED;
        }
        let node = self.simplify(node, value);
        if let Node::Const(c) = node
            && let Some(&id) = self.known.get(&NodeKey::Const(c.to_bits()))
        {
            return id;
        }
        if let Some(forward) = self.forward(&node) {
            return forward;
        }
        let key = key_of(&node);
        if let Some(&id) = self.known.get(&key) {
            return id;
        }
        let id = self.tape.nodes.len() as NodeId;
        self.tape.nodes.push(node);
        self.values.push(value);
        self.known.insert(key, id);
        id
    }

    /// The node itself when its operands are constants (the value the
    /// evaluation computed), else the node.
    fn simplify(&self, node: Node, value: f64) -> Node {
        let constant =
            !matches!(node, Node::Input(_)) && operands(&node).all(|o| self.constant(o).is_some());
        if constant { Node::Const(value) } else { node }
    }

    /// An operand the node equals: `x * 1`, `1 * x`, `x / 1`, `x + 0`,
    /// `0 + x`, `x - 0`, `-(-x)`; a zero for a product with a zero
    /// coefficient; and the same number by a cheaper operation: `-x` for
    /// `x * -1`, `a - b` for `a + (-b)`, `a + b` for `a - (-b)` (IEEE
    /// subtraction is the addition of the negation).
    fn forward(&mut self, node: &Node) -> Option<NodeId> {
        let is = |r: &Self, id: NodeId, c: f64| r.constant(id).is_some_and(|v| v == c);
        let negated = |r: &Self, id: NodeId| match r.tape.nodes[id as usize] {
            Node::Neg(inner) => Some(inner),
            _ => None,
        };
        let value = |r: &Self, id: NodeId| r.values[id as usize];
        match *node {
            Node::Neg(a) if let Some(inner) = negated(self, a) => Some(inner),
            Node::Mul(a, b) if is(self, b, -1.0) => Some(self.push(Node::Neg(a), -value(self, a))),
            Node::Mul(a, b) if is(self, a, -1.0) => Some(self.push(Node::Neg(b), -value(self, b))),
            Node::Add(a, b) if let Some(inner) = negated(self, b) => {
                Some(self.push(Node::Sub(a, inner), value(self, a) - value(self, inner)))
            }
            Node::Sub(a, b) if let Some(inner) = negated(self, b) => {
                Some(self.push(Node::Add(a, inner), value(self, a) + value(self, inner)))
            }
            Node::Mul(a, b) if is(self, b, 1.0) => Some(a),
            Node::Mul(a, b) if is(self, a, 1.0) => Some(b),
            Node::Div(a, b) if is(self, b, 1.0) => Some(a),
            Node::Add(a, b) if is(self, b, 0.0) => Some(a),
            Node::Add(a, b) if is(self, a, 0.0) => Some(b),
            Node::Sub(a, b) if is(self, b, 0.0) => Some(a),
            Node::Mul(a, b) if is(self, a, 0.0) || is(self, b, 0.0) => Some(self.push_zero()),
            _ => None,
        }
    }

    fn push_zero(&mut self) -> NodeId {
        self.push(Node::Const(0.0), 0.0)
    }
}
