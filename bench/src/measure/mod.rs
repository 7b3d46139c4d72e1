//! The parts of `measure` (the binary `src/bin/measure.rs`): the command line, the suites'
//! plan of commands, running them, reading their outputs and the table.

pub mod cli;
pub mod error;
pub mod md5;
pub mod plan;
pub mod read;
pub mod run;
pub mod table;
