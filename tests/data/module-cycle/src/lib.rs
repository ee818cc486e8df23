//! Fixture: two modules in a cycle, for scripts/module_cycles.py.
mod a;
mod b;
