//! The baselines UPETrack is compared with, each a [`crate::step::TrackingStep`]
//! with its own settings: [`cpd`] (deformable coherent point drift from the
//! previous nodes) and [`trackdlo`] (TrackDLO, reimplemented). They share
//! every other stage with UPETrack, so the comparison is of tracking steps.

pub mod cpd;
pub mod trackdlo;
