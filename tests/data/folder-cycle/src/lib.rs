//! Fixture: no two files import each other, but folder `x` uses `y` and
//! `y` uses `x`; scripts/module_cycles.py must report it.
mod x;
mod y;
