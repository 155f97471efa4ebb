//! The errors of reading EXR files (`eval`'s inputs, `render --input` checks): the `exr`
//! crate's errors mapped to day2night's kinds, shared by the chunk checks
//! ([`super::chunks`]) and the image reader ([`crate::encode::read`]).

use crate::error::Error;

/// day2night's error for an error of the `exr` crate.
pub(crate) fn exr_err(e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            Error::malformed("EXR: file is truncated")
        }
        exr::error::Error::Io(io) => Error::Io(io),
        exr::error::Error::NotSupported(m) => Error::unsupported(format!("EXR: {m}")),
        exr::error::Error::Invalid(m) => Error::malformed(format!("EXR: {m}")),
        exr::error::Error::Aborted => Error::malformed("EXR: reading aborted"),
    }
}
