//! An EXR written from its stored blocks, band by band ([`ExrFile`]) or all at once
//! ([`write_exr_blocks`]), so that the encoded image is never held whole.

use super::{scanline, ExrOptions};
use crate::error::{Error, Result, ResultExt};
use crate::output::{AtomicFile, OutputPolicy};
use std::path::Path;

/// Write a `width` x `height` EXR from its stored `blocks` (all of them, in line order, from
/// [`encode_exr_rows`](super::encode_exr_rows) with the same `opts`) atomically at `path`
/// (through [`ExrFile`]).
pub fn write_exr_blocks(
    width: usize,
    height: usize,
    blocks: &[Vec<u8>],
    path: &Path,
    opts: &ExrOptions,
    attributes: &[(String, String)],
    policy: &OutputPolicy,
) -> Result<()> {
    opts.validate()?;
    if width == 0 || height == 0 {
        return Err(Error::invalid("cannot write an empty EXR image"));
    }
    scanline::check_attributes(attributes)?;
    if let Some(lpb) = scanline::lines_per_block(opts.compression) {
        let nblocks = height.div_ceil(lpb);
        if blocks.len() != nblocks {
            return Err(Error::invalid(format!(
                "EXR of {height} lines needs {nblocks} blocks, got {}",
                blocks.len()
            )));
        }
    }
    let mut file = ExrFile::create(path, width, height, opts, attributes, policy)?;
    for blk in blocks {
        file.push_block(blk)?;
    }
    file.finish()
}

/// An EXR target written while it is rendered: the blocks of each band of rows
/// ([`encode_exr_rows`](super::encode_exr_rows)) are appended as they come, in line order,
/// so the encoded image is never held whole. [`ExrFile::create`] writes the header and a
/// zeroed offset table into an [`AtomicFile`], [`ExrFile::push_rows`] appends blocks,
/// [`ExrFile::finish`] fills in the offset table and syncs and renames the file into place.
/// The bytes are those of [`write_exr`](super::write_exr) of the whole image (tested);
/// dropped unfinished, nothing appears at `path`.
#[derive(Debug)]
pub struct ExrFile<'p> {
    file: AtomicFile<'p>,
    stream: scanline::BlockStream,
}

impl<'p> ExrFile<'p> {
    /// Start a `width` x `height` EXR at `path` (options and attributes as for
    /// [`write_exr_blocks`]; `opts` must be one [`encodes_rows`](super::encodes_rows)
    /// accepts).
    pub fn create(
        path: &Path,
        width: usize,
        height: usize,
        opts: &ExrOptions,
        attributes: &[(String, String)],
        policy: &'p OutputPolicy,
    ) -> Result<ExrFile<'p>> {
        opts.validate()?;
        if width == 0 || height == 0 {
            return Err(Error::invalid("cannot write an empty EXR image"));
        }
        scanline::check_attributes(attributes)?;
        let mut file = AtomicFile::create(path, policy)?;
        let stream = scanline::BlockStream::begin(file.writer()?, width, height, opts, attributes)
            .in_file(path)?;
        Ok(ExrFile { file, stream })
    }

    /// Append the `blocks` of the rows from image line `first_row`, which must be the first
    /// line not written yet.
    pub fn push_rows(&mut self, first_row: usize, blocks: &[Vec<u8>]) -> Result<()> {
        let next = self.stream.next_line();
        if first_row != next {
            return Err(Error::invalid(format!(
                "EXR rows from line {first_row} given while line {next} is the next to write"
            ))
            .in_file(self.file.path()));
        }
        for blk in blocks {
            self.push_block(blk)?;
        }
        Ok(())
    }

    fn push_block(&mut self, block: &[u8]) -> Result<()> {
        let r = self.file.writer().and_then(|w| self.stream.push(w, block));
        r.in_file(self.file.path())
    }

    /// Write the offset table (every block must have been pushed), then sync and rename
    /// the file into place (see [`AtomicFile::finish`]).
    pub fn finish(mut self) -> Result<()> {
        let r = self.file.writer().and_then(|w| self.stream.finish(w));
        r.in_file(self.file.path())?;
        self.file.finish()
    }
}
