/// How a push missed: the larger of its errors along and across the demonstration's push
/// decides ([`PushError::miss`](super::PushError::miss)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PushMiss {
    /// Pushed too little.
    Short,
    /// Pushed too far.
    Long,
    /// Knocked aside: the push met the object off its centre.
    Aside,
}
