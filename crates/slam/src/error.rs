//! The crate's error type.

/// What can be wrong with the front end's parameters or the trajectories given to evaluation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SlamError {
    /// A parameter is outside its valid range.
    #[error("{key} = {value} {requirement}")]
    InvalidParam {
        /// The parameter's name.
        key: &'static str,
        /// Its value, as text.
        value: String,
        /// What it must satisfy.
        requirement: &'static str,
    },
    /// Two trajectories to compare differ in length.
    #[error("the estimate has {estimate} poses, the reference {reference}")]
    LengthMismatch {
        /// Poses of the estimate.
        estimate: usize,
        /// Poses of the reference.
        reference: usize,
    },
    /// Too few poses for the measure asked for.
    #[error("{what} needs at least {needed} poses, {got} given")]
    TooFewPoses {
        /// The measure.
        what: &'static str,
        /// Poses it needs.
        needed: usize,
        /// Poses given.
        got: usize,
    },
    /// An edge names a node the graph does not have, or joins a node to itself.
    #[error("edge {from} -> {to} does not join two of the graph's {nodes} nodes")]
    BadEdge {
        /// Its first node.
        from: usize,
        /// Its second node.
        to: usize,
        /// Nodes in the graph.
        nodes: usize,
    },
    /// The pose graph's normal equations could not be solved.
    #[error("the pose graph is singular: a node is not tied to the first by any measurement")]
    SingularGraph,
}
