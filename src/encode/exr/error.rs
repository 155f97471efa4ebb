//! The errors of the EXR reading path (`eval`'s inputs) in plain words, shared by the chunk
//! checks ([`super::chunks`]) and the image reader ([`crate::encode::read`]). The `exr`
//! crate's messages are terse and name its internals ("compressed DWAB(None) data
//! (invalid: truncated DWA header)", "invalid: line order attribute value"); `exr_err`
//! turns each of them into a sentence that says what is wrong with the file, and
//! `chunk_err` says which chunk (number, rows, compression) a decoding error comes from.
//! `guarded` runs the decoder so that a panic on damaged data is an error (and prints
//! nothing).
//!
//! Every message the crate (1.74) can give while reading is listed in `MESSAGES` with its
//! sentence; the unit tests check that each is mapped and that no sentence carries an
//! internal name. A message the table does not know (a newer crate) is passed on only when
//! it is made of plain words.

use crate::error::{Error, Result};
use std::cell::Cell;

/// How a message of the crate is matched.
#[derive(Debug, Clone, Copy)]
enum Match {
    Exact,
    Prefix,
    Contains,
}

use Match::{Contains, Exact, Prefix};

/// Messages the `exr` crate gives while reading, and what they mean. Sentences about one
/// chunk's data start with "its" (they follow "chunk N (...) is damaged: ").
#[rustfmt::skip]
const MESSAGES: &[(Match, &str, &str)] = &[
    // The file and its version field.
    (Exact, "file identifier missing", "the file does not start with the OpenEXR magic number"),
    (Exact, "file feature flags", "the version field has feature flags OpenEXR does not define"),
    (Exact, "too new file feature flags", "the version field has feature flags newer than this reader knows"),
    (Exact, "file versions other than 2.0 are not supported", "the OpenEXR format version is not 2"),
    (Contains, "deep", "the file holds deep data, which eval cannot read"),
    (Exact, "max sample count", "the file holds deep data, which eval cannot read"),
    (Exact, "at least one layer is required", "the file has no image part"),
    (Exact, "no layer in the image matched your specified requirements", "the file has no image part with colour channels"),
    (Prefix, "layer does not contain all of your specified channels", "a channel is missing from the image part"),
    (Exact, "invalid header", "the header's data window does not fit its chunks"),
    // Header attributes.
    (Prefix, "missing or invalid channels attribute", "the header has no valid channel list"),
    (Prefix, "missing or invalid compression attribute", "the header has no valid compression attribute"),
    (Prefix, "missing or invalid data window attribute", "the header has no valid data window"),
    (Prefix, "missing or invalid display window attribute", "the header has no valid display window"),
    (Prefix, "missing or invalid tiles attribute", "the header of a tiled image has no valid tile description"),
    (Prefix, "missing or invalid layer name", "a part of the multi-part file has no name"),
    (Prefix, "missing or invalid", "the header misses an attribute OpenEXR requires"),
    (Prefix, "duplicate attribute name", "the header has the same attribute twice"),
    (Prefix, "duplicate layer name", "two parts of the file have the same name"),
    (Contains, "is reserved and cannot be custom", "the header uses a reserved attribute name for its own attribute"),
    (Exact, "attribute type mismatch", "an attribute of the header has the wrong type for its name"),
    (Exact, "attribute size", "an attribute of the header has an impossible size"),
    (Prefix, "text", "a text attribute of the header has an impossible length"),
    (Exact, "vector size", "a list attribute of the header has an impossible length"),
    (Exact, "block type attribute value", "the header's part type is none of those OpenEXR defines"),
    (Exact, "line order attribute value", "the header's line order is none of increasing, decreasing or random"),
    (Exact, "pixel type attribute value", "a channel's sample type is none of half, float or unsigned int"),
    (Exact, "channel linearity attribute value", "a channel's linearity flag is neither 0 nor 1"),
    (Exact, "environment map attribute value", "the header's environment map type is none of those OpenEXR defines"),
    (Exact, "tile description level mode", "the tile description's level mode is none of one level, mipmap or ripmap"),
    (Exact, "tile description rounding mode", "the tile description's rounding mode is neither down nor up"),
    (Exact, "tile size", "the tile size is zero or too large"),
    (Exact, "window attribute dimension value", "a window of the header (data or display window) has a negative size"),
    (Exact, "window size exceeding integer maximum", "a window of the header is too large"),
    (Exact, "empty data window", "the data window is empty"),
    (Exact, "empty display window", "the display window is empty"),
    (Exact, "unspecified line order in scan line images", "the header of a scan-line image says its line order is random"),
    (Exact, "pixel aspect ratio", "the pixel aspect ratio is not a positive finite number"),
    (Exact, "screen window width", "the screen window width is not a positive finite number"),
    (Prefix, "chunk count", "the header's chunk count does not match its data window"),
    (Exact, "channel subsampling not supported yet", "a channel is subsampled, which eval cannot read"),
    (Contains, "sampling", "a channel's subsampling factors do not fit the data window"),
    (Exact, "at least one channel is required", "the header lists no channel"),
    (Exact, "channel names are not unique", "two channels have the same name"),
    (Exact, "channel names are not sorted alphabetically", "the channel list is not in alphabetical order"),
    (Prefix, "time code", "the time code attribute holds an impossible value"),
    (Exact, "unknown compression method", "the header names a compression method OpenEXR does not define"),
    (Contains, "preview", "the preview image attribute's size does not match its data"),
    (Contains, "must be equal for all headers", "the parts of the multi-part file disagree on the attributes they must share"),
    (Contains, "must must not exist in own attributes", "a part of the multi-part file has its own copy of an attribute the parts must share"),
    (Prefix, "invalid cropping bounds", "the image part's data window is invalid"),
    (Exact, "inferred requirements are invalid", "the image part's data window is invalid"),
    // Offset table and chunk positions.
    (Exact, "chunk offset table", "the chunk offset table is damaged"),
    (Exact, "offset table", "the chunk offset table is damaged"),
    (Exact, "end of file expected", "there are bytes after the last chunk"),
    (Exact, "scan block y coordinate", "a chunk's first row lies outside the data window"),
    (Exact, "data block tile index", "a tile's position lies outside the image"),
    (Exact, "tile index", "a tile's position lies outside the image"),
    (Prefix, "tile ", "a tile's position lies outside the image"),
    (Prefix, "level ", "a tile's resolution level lies outside the image"),
    (Prefix, "mip level index", "a tile's resolution level lies outside the image"),
    (Prefix, "rip level index", "a tile's resolution level lies outside the image"),
    (Exact, "chunk data part number", "a chunk names an image part the file does not have"),
    (Exact, "chunk layer index", "a chunk names an image part the file does not have"),
    (Exact, "layer index", "a chunk names an image part the file does not have"),
    (Exact, "chunk start", "a chunk's position is damaged"),
    (Exact, "data indices start", "a chunk's position lies outside the data window"),
    (Exact, "pixel index", "a chunk's position lies outside the data window"),
    (Exact, "box coordinates", "a chunk's position lies outside the data window"),
    (Prefix, "block position", "a chunk lies outside the image"),
    (Exact, "reference to missing bytes", "the file ends early (truncated?)"),
    (Exact, "integer conversion failed: value out of range", "a size or position in the file is out of range"),
    (Prefix, "decompressed block byte size mismatch", "its pixels decompress to the wrong number of bytes"),
    (Exact, "parallel decompression requires the rayon feature", "the decoder was built without the parallel reader"),
    // One chunk's compressed data.
    (Exact, "zlib-compressed data malformed", "its zlib stream does not decode"),
    (Exact, "compression data", "its compressed bytes are damaged"),
    (Exact, "compressed data", "its compressed bytes are damaged"),
    (Exact, "data amount", "its compressed bytes are damaged"),
    (Exact, "decompressed data", "it decompresses to the wrong number of bytes"),
    (Exact, "not enough data", "its compressed bytes end early"),
    (Exact, "too much data", "it holds more compressed bytes than its pixels need"),
    (Exact, "invalid number of bits", "its Huffman code table has an impossible code length"),
    (Exact, "invalid code table entry", "its Huffman code table is damaged"),
    (Exact, "unexpected end of code table data", "its Huffman code table ends early"),
    (Exact, "code table is longer than expected", "its Huffman code table is longer than it says"),
    (Exact, "invalid code", "it holds an invalid Huffman code"),
    (Exact, "code", "it holds an invalid Huffman code"),
    (Exact, "table entry", "its Huffman code table is damaged"),
    (Exact, "decoded data are shorter than expected", "its Huffman-coded data decode to fewer values than its pixels need"),
    (Exact, "decoded data are longer than expected", "its Huffman-coded data decode to more values than its pixels need"),
    (Contains, "huffman", "its Huffman-coded data are damaged"),
    (Exact, "long code index", "its Huffman-coded data are damaged"),
    (Exact, "DWA lossy DCT compression of u32 channels", "DWA compression of 32-bit integer channels is not supported"),
    (Contains, "truncated DWA", "its DWA data end early"),
    (Contains, "DWA input data truncated", "its DWA data end early"),
    (Contains, "DWA", "its DWA data are damaged"),
    (Prefix, "yet unimplemented compression special case", "it uses a form of its compression this reader does not implement"),
    (Prefix, "yet unimplemented compression method", "its compression method is not implemented by this reader"),
];

/// The sentence for a message of the crate (without its "invalid: " / "not supported: "
/// prefix), or `None`.
fn sentence(msg: &str) -> Option<&'static str> {
    MESSAGES.iter().find_map(|&(how, key, s)| {
        let hit = match how {
            Exact => msg == key,
            Prefix => msg.starts_with(key),
            Contains => msg.contains(key),
        };
        hit.then_some(s)
    })
}

/// True for text made of words only (no code names, brackets or backticks).
fn plain_words(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || " ,.'-".contains(c))
        && !s.contains("  ")
        && !s
            .split(' ')
            .any(|w| w.contains('_') || w.chars().skip(1).any(|c| c.is_ascii_uppercase()))
}

/// The name of an EXR compression as users know it ("ZIP", "PIZ", "DWAB", "uncompressed").
pub(crate) fn compression_name(c: exr::compression::Compression) -> String {
    let shown = c.to_string();
    let base = shown.strip_suffix(" compression").unwrap_or(&shown);
    match base {
        "no" => "uncompressed".into(),
        "zip line" => "ZIPS".into(),
        "zip block" => "ZIP".into(),
        other if other.starts_with("ht j2k") => "HTJ2K".into(),
        other => other.to_ascii_uppercase(),
    }
}

/// A message of the crate: "compressed <Debug> data (<inner>)" split into the compression
/// (as users name it) and the inner message; else `None`.
fn decompression(msg: &str) -> Option<(String, String)> {
    let rest = msg.strip_prefix("compressed ")?;
    let (name, inner) = rest.split_once(" data (")?;
    let inner = inner.strip_suffix(')').unwrap_or(inner);
    let inner = inner
        .strip_prefix("invalid: ")
        .or_else(|| inner.strip_prefix("not supported: "))
        .unwrap_or(inner);
    let base = name.split('(').next().unwrap_or(name);
    let shown = match base {
        "Uncompressed" => "uncompressed".to_string(),
        "ZIP1" => "ZIPS".into(),
        "ZIP16" => "ZIP".into(),
        b if b.starts_with("HTJ2K") => "HTJ2K".into(),
        b => b.to_ascii_uppercase(),
    };
    Some((shown, inner.to_string()))
}

/// What is wrong with one chunk, after "is damaged: ".
fn chunk_problem(inner: &str) -> String {
    match sentence(inner) {
        Some(s) => s.to_string(),
        None if plain_words(inner) => format!("the decoder says: {inner}"),
        None => "its data do not decode".into(),
    }
}

/// The crate's message in plain words (no "EXR: " prefix).
fn plain(msg: &str) -> String {
    if let Some((compression, inner)) = decompression(msg) {
        return format!(
            "a {compression}-compressed chunk is damaged: {}",
            chunk_problem(&inner)
        );
    }
    match sentence(msg) {
        Some(s) if s.starts_with("its ") || s.starts_with("it ") => {
            format!("a chunk is damaged: {s}")
        }
        Some(s) => s.into(),
        None if plain_words(msg) => format!("the file is damaged (the decoder says: {msg})"),
        None => "the file is damaged".into(),
    }
}

/// An error of the `exr` crate as a day2night error in plain words: "malformed input: EXR:
/// the header's line order is none of increasing, decreasing or random".
pub(crate) fn exr_err(e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            Error::malformed("EXR: the file ends early (truncated?)")
        }
        exr::error::Error::Io(io) => Error::Io(io),
        exr::error::Error::NotSupported(m) => Error::unsupported(format!("EXR: {}", plain(&m))),
        exr::error::Error::Invalid(m) => Error::malformed(format!("EXR: {}", plain(&m))),
        exr::error::Error::Aborted => Error::malformed("EXR: reading was cancelled"),
    }
}

/// Where a chunk sits: "chunk 12 of 32 (rows 192..208, ZIP compression)".
#[derive(Debug, Clone)]
pub(crate) struct ChunkPlace {
    /// Chunk number, 0-based, in the file's chunk order (`None`: its position is outside
    /// the image).
    pub index: Option<usize>,
    /// Chunks in the file.
    pub count: usize,
    /// "rows 192..208" or "tile (2, 3), level (0, 0)".
    pub pixels: String,
    /// Its compression, as [`compression_name`] gives it.
    pub compression: String,
}

impl ChunkPlace {
    /// "chunk 12 of 32 (rows 192..208, ZIP compression)", or "a chunk (first row 9000,
    /// outside the data window, ZIP compression)".
    pub fn describe(&self) -> String {
        let which = match self.index {
            Some(i) => format!("chunk {i} of {}", self.count),
            None => "a chunk".into(),
        };
        format!(
            "{which} ({}, {} compression)",
            self.pixels, self.compression
        )
    }
}

/// An error of the crate while decoding the chunk at `place`: "EXR: chunk 12 of 32 (rows
/// 192..207, ZIP compression) is damaged: its zlib stream does not decode".
pub(crate) fn chunk_err(e: exr::error::Error, place: &ChunkPlace) -> Error {
    let (what, unsupported) = match &e {
        exr::error::Error::Io(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => {
            return Error::Io(std::io::Error::new(io.kind(), io.to_string()));
        }
        exr::error::Error::Io(_) => ("its bytes run past the end of the file".to_string(), false),
        exr::error::Error::NotSupported(m) | exr::error::Error::Invalid(m) => {
            let inner = decompression(m).map_or_else(|| m.to_string(), |(_, i)| i);
            let s = sentence(&inner);
            let what = match s {
                Some(s) if s.starts_with("its ") || s.starts_with("it ") => s.to_string(),
                Some(s) => s.to_string(),
                None => chunk_problem(&inner),
            };
            (what, matches!(e, exr::error::Error::NotSupported(_)))
        }
        exr::error::Error::Aborted => ("reading was cancelled".into(), false),
    };
    let text = format!(
        "EXR: {} {}: {what}",
        place.describe(),
        if unsupported {
            "cannot be read"
        } else {
            "is damaged"
        }
    );
    if unsupported {
        Error::unsupported(text)
    } else {
        Error::malformed(text)
    }
}

thread_local! {
    /// Set while [`guarded`] runs on this thread: its panics are errors, not messages.
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

/// Run the decoder `f` on untrusted data: a panic in it is `failed` (an error), and the
/// panic's message is not printed (the process-wide panic hook is wrapped once so that it
/// stays silent on this thread while `f` runs; every other panic is reported as before).
pub(crate) fn guarded<T>(
    f: impl FnOnce() -> Result<T>,
    failed: impl FnOnce() -> Error,
) -> Result<T> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
    let was = QUIET.with(|q| q.replace(true));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(was));
    r.unwrap_or_else(|_| Err(failed()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every message the crate's reading path can give (exr 1.74: `Error::invalid` and
    /// `Error::unsupported` literals, the `purpose`/`error_message` strings of its
    /// readers, and the formats), as they reach [`exr_err`].
    #[rustfmt::skip]
    const CRATE_MESSAGES: &[&str] = &[
        "file identifier missing", "file feature flags", "too new file feature flags",
        "file versions other than 2.0 are not supported", "deep data not supported yet",
        "deep data version", "compression method does not support deep data",
        "`SpecificChannels` does not support deep data yet", "at least one layer is required",
        "no layer in the image matched your specified requirements",
        "layer does not contain all of your specified channels (`R` is missing)", "invalid header",
        "missing or invalid channels attribute", "missing or invalid compression attribute",
        "missing or invalid data window attribute", "missing or invalid display window attribute",
        "missing or invalid tiles attribute",
        "missing or invalid layer name for deep file attribute",
        "missing or invalid deep data version attribute",
        "missing max samples per pixel attribute for deepdata", "duplicate attribute name: `foo`",
        "duplicate layer name: `left`",
        "attribute name `channels` is reserved and cannot be custom", "attribute type mismatch",
        "attribute size", "text must not be empty", "text must not be longer than 255",
        "text too long", "text array byte size", "text vector may not be empty", "text length",
        "text size bug", "vector size", "block type attribute value", "line order attribute value",
        "pixel type attribute value", "channel linearity attribute value",
        "environment map attribute value", "tile description level mode",
        "tile description rounding mode", "tile size", "window attribute dimension value",
        "window size exceeding integer maximum", "empty data window", "empty display window",
        "unspecified line order in scan line images", "pixel aspect ratio", "screen window width",
        "chunk count attribute", "chunk count not matching data size", "chunk count",
        "zero sampling factor", "subsampling is only allowed in flat scan line images",
        "channel sampling factor not dividing data window position",
        "channel sampling factor not dividing data window size",
        "channel subsampling not supported yet", "sampling", "sampling factor",
        "x channel sampling", "y channel sampling", "at least one channel is required",
        "channel names are not unique", "channel names are not sorted alphabetically",
        "time code frame larger than 29", "time code seconds larger than 59",
        "time code minutes larger than 59", "time code hours larger than 23",
        "time code binary group value too large for 3 bits", "unknown compression method",
        "preview dimensions do not match content length",
        "Overflow while calculating preview image Attribute size (width: 3, height: 4).",
        "display window, pixel aspect, chromaticities, and time code attributes must be equal for all headers",
        "chromaticities and time code attributes must must not exist in own attributes but shared instead",
        "invalid cropping bounds for cropped view", "inferred requirements are invalid",
        "chunk offset table", "offset table", "end of file expected", "scan block y coordinate",
        "data block tile index", "tile index", "tile x", "tile y", "tile coordinate level",
        "tile coordinate index", "level index exceeding integer maximum", "level x", "level y",
        "mip level index 3 out of range (max: 1)", "rip level index Vec2(1, 2) not found",
        "chunk data part number", "chunk layer index", "layer index", "chunk start",
        "data indices start", "pixel index", "box coordinates",
        "block position 40 exceeds total size 32", "reference to missing bytes",
        "integer conversion failed: value out of range",
        "decompressed block byte size mismatch: expected 12 bytes but got 8 bytes",
        "parallel decompression requires the rayon feature", "raw deep size", "deep table size",
        "deep size", "max sample count", "zlib-compressed data malformed", "compression data",
        "compressed data", "data amount", "decompressed data", "not enough data", "too much data",
        "invalid number of bits", "invalid code table entry", "unexpected end of code table data",
        "code table is longer than expected", "invalid code", "code",
        "decoded data are shorter than expected", "decoded data are longer than expected",
        "huffman code index", "huffman start index", "huffman long code", "huffman count",
        "long code index", "table entry", "DWA channel rule csc index out of range",
        "truncated DWA channel rules", "corrupt DWA channel rule", "DWA channel rules too large",
        "truncated DWA section", "DWA zlib data malformed", "DWA zlib data size mismatch",
        "DWA f16 channel data size", "DWA f32 channel data size",
        "DWA lossy DCT compression of u32 channels", "DWA lossy channel data size mismatch",
        "invalid DWA lossy component count", "DWA lossy component size mismatch",
        "truncated DWA DC data", "truncated DWA AC data", "truncated DWA header",
        "DWA counter out of range", "unknown DWA AC compression mode", "DWA input data truncated",
        "DWA input data size mismatch", "truncated DWA channel data", "DWA decoded size mismatch",
        "yet unimplemented compression special case (some case)",
        "yet unimplemented compression method: ht j2k 32 compression",
        "compressed DWAB(None) data (invalid: truncated DWA header)",
        "compressed ZIP16 data (invalid: zlib-compressed data malformed)",
        "compressed PIZ data (invalid: invalid code)",
        "compressed B44A data (invalid: not enough data)",
        "compressed RLE data (not supported: something)",
    ];

    /// Words and shapes of the crate's internals that must not reach a user.
    fn internal(s: &str) -> Option<&'static str> {
        [
            "DWAB(",
            "DWAA(",
            "ZIP16",
            "ZIP1 ",
            "None)",
            "Vec2",
            "attribute value",
            "invalid:",
            "not supported:",
            "`",
            "_",
            "bug",
            "yet",
            "deepdata",
        ]
        .into_iter()
        .find(|w| s.contains(w))
    }

    #[test]
    fn every_crate_message_becomes_a_sentence_without_internal_names() {
        for m in CRATE_MESSAGES {
            let plain_form = plain(m);
            assert!(
                !plain_form.starts_with("the file is damaged"),
                "{m:?} is not in the table: {plain_form}"
            );
            for e in [
                exr_err(exr::error::Error::Invalid((*m).to_string().into())),
                exr_err(exr::error::Error::NotSupported((*m).to_string().into())),
            ] {
                let s = e.to_string();
                assert!(
                    internal(&s).is_none(),
                    "{m:?} -> {s:?} shows {:?}",
                    internal(&s)
                );
            }
            let place = ChunkPlace {
                index: Some(3),
                count: 8,
                pixels: "rows 48..64".into(),
                compression: "ZIP".into(),
            };
            let s =
                chunk_err(exr::error::Error::Invalid((*m).to_string().into()), &place).to_string();
            assert!(internal(&s).is_none(), "{m:?} -> {s:?}");
        }
        // The two examples.
        let e = exr_err(exr::error::Error::Invalid(
            "compressed DWAB(None) data (invalid: truncated DWA header)".into(),
        ));
        assert_eq!(
            e.to_string(),
            "malformed input: EXR: a DWAB-compressed chunk is damaged: its DWA data end early"
        );
        let e = exr_err(exr::error::Error::Invalid(
            "line order attribute value".into(),
        ));
        assert_eq!(
            e.to_string(),
            "malformed input: EXR: the header's line order is none of increasing, decreasing or random"
        );
        let place = ChunkPlace {
            index: Some(12),
            count: 32,
            pixels: "rows 192..208".into(),
            compression: "ZIP".into(),
        };
        let e = chunk_err(
            exr::error::Error::Invalid(
                "compressed ZIP16 data (invalid: zlib-compressed data malformed)".into(),
            ),
            &place,
        );
        assert_eq!(
            e.to_string(),
            "malformed input: EXR: chunk 12 of 32 (rows 192..208, ZIP compression) is damaged: its zlib stream does not decode"
        );
    }

    #[test]
    fn unknown_messages_pass_only_as_plain_words() {
        assert_eq!(
            plain("a brand new problem"),
            "the file is damaged (the decoder says: a brand new problem)"
        );
        assert_eq!(plain("FooBar(Some(3)) value"), "the file is damaged");
        assert!(plain_words("the file is damaged, badly"));
        assert!(!plain_words("snake_case"));
        assert!(!plain_words("CamelCase thing"));
    }

    #[test]
    fn compression_names_are_the_users() {
        use exr::compression::Compression as C;
        assert_eq!(compression_name(C::ZIP16), "ZIP");
        assert_eq!(compression_name(C::ZIP1), "ZIPS");
        assert_eq!(compression_name(C::Uncompressed), "uncompressed");
        assert_eq!(compression_name(C::PIZ), "PIZ");
        assert_eq!(compression_name(C::B44A), "B44A");
    }

    #[test]
    fn a_panic_in_the_guard_is_a_quiet_error_and_others_still_report() {
        let r: Result<()> = guarded(|| panic!("decoder bug"), || Error::malformed("EXR: failed"));
        assert_eq!(r.unwrap_err().to_string(), "malformed input: EXR: failed");
        assert_eq!(guarded(|| Ok(3), || Error::malformed("x")).unwrap(), 3);
        assert!(!QUIET.with(Cell::get));
    }
}
