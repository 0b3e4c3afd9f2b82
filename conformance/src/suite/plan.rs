//! A case's plan, before it is built: the steps it sends and how each answer is written
//! (exactly, or elided where the protocol lets it vary), with the captures and relations on
//! the answers' values. [`super::build`] turns a plan into a golden; [`super::depends`] reads
//! one for the decisions its steps touch.

use std::time::Duration;

use gcl_transcript::Relation;
use gcl_transcript::script::ScriptStep;

/// An inclusive range of values.
pub(crate) type Range = (i64, i64);

/// How the answer of a planned step is written.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Shape {
    /// Exactly as the model answers.
    Exact,
    /// A RESET banner: `{any}BarrettHand Firmware{any}`.
    Banner,
    /// A RESET banner checked for what hosts rely on: the echo, any text, `BarrettHand
    /// Firmware` then the line ending straight after it, at least one more byte of banner,
    /// then the line ending and the prompt.
    BannerLines,
    /// Value lines after the echo: for line `i`, token `j`, a range (or exact).
    Values(Vec<Vec<Option<Range>>>),
    /// List lines `NAME value...`: values of live parameters elided to their ranges.
    ListValues,
    /// The echo, then `{text}`: one or more lines of text, none of them a status answer (text
    /// the project chose: only that there is some, and that it is not `ERR n`, is checked).
    AnyLines,
    /// A RealTime answer: a feedback block with per-field rules (see [`FieldRule`]).
    Block(Vec<FieldRule>),
}

/// An override for one feedback field.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FieldRule {
    /// The motor, or `None` for a hand-wide field.
    pub motor: Option<u8>,
    /// The flag name (LFAP, LFDP, ...).
    pub name: &'static str,
    /// The accepted range (`None`: exact).
    pub range: Option<Range>,
}

/// Which value of an answer a [`Bind`] applies to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Target {
    /// A feedback field of a RealTime answer (a [`Shape::Block`]).
    Field {
        /// The motor, or `None` for a hand-wide field.
        motor: Option<u8>,
        /// The flag name.
        name: &'static str,
    },
    /// Token `token` of value line `line` of a [`Shape::Values`] answer (0-based).
    Value { line: usize, token: usize },
}

/// A value of an answer captured under a name, or held to a relation with a value captured
/// before it, or both. A relation is the case's subject written as arithmetic between two
/// answers, so that the case does not rest on the absolute values another decision sets;
/// it carries its evidence, which the golden states as a note.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Bind {
    pub target: Target,
    pub capture: Option<String>,
    pub relation: Option<Relation>,
    /// Why the relation holds: the clause it writes down and how its factor and tolerance
    /// follow from the model.
    pub evidence: String,
    /// Pairs (captured value, related value) the model gives over every situation the case
    /// allows: each must lie in the relation's band, or the case is not built.
    pub samples: Vec<(i64, i64)>,
}

/// One planned step.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Plan {
    pub step: ScriptStep,
    pub shape: Shape,
    pub within_floor: Option<Duration>,
    /// The soonest the answer may come (a timing window's lower bound), with its evidence.
    pub earliest: Option<(Duration, String)>,
    /// Captures and relations on the answer's values.
    pub binds: Vec<Bind>,
}
