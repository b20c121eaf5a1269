//! What the scene front-ends that translate another format into TOML (POV-Ray, Mitsuba) share:
//! a place in the source files and an error that may carry one.

use std::fmt;

/// A place in a front-end's scene file or one of its includes: file number (see each
/// front-end's `Translation::files`), line and column, from 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pos {
    pub file: u32,
    pub line: u32,
    pub col: u32,
}

/// An error of a front-end, at a position when it has one.
#[derive(Clone, Debug)]
pub struct FrontEndError {
    pub pos: Option<Pos>,
    pub message: String,
}

impl FrontEndError {
    pub fn at(pos: Pos, message: String) -> FrontEndError {
        FrontEndError { pos: Some(pos), message }
    }
}

impl fmt::Display for FrontEndError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&self.message)
    }
}
