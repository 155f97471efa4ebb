//! Dataset report (in progress).
