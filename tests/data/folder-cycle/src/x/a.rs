use crate::y::b::B;
