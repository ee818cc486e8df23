use crate::x::d::D;
