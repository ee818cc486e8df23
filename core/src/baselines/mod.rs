//! The baselines UPETrack is compared with, each a [`crate::step::TrackingStep`]
//! with its own settings: [`cpd`] (deformable coherent point drift from the
//! previous nodes), [`trackdlo`] (TrackDLO, reimplemented) and `cdcpd2`
//! (CDCPD2 with a convex QP, feature `cdcpd2`). They share every other
//! stage with UPETrack, so the comparison is of tracking steps.

#[cfg(feature = "cdcpd2")]
pub mod cdcpd2;
pub mod cpd;
pub mod trackdlo;
