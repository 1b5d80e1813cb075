//! 8-bit grey images stored as binary PGM (`P5`, maxval 255), the simplest format any language can write, either
//! plain (`.pgm`) or inside one Zstandard frame (`.pgm.zst`, RFC 8878), which a webcam's dark IR frames shrink
//! to about a tenth (docs/recording.md, "Frames").

use crate::error::RecordError;
use std::path::Path;

/// File-name suffix of a Zstandard-compressed PGM.
pub const ZSTD_SUFFIX: &str = ".zst";

/// Zstandard level of compressed frames. On the `webcam` scenario's dark IR frames level 6 gives 23.5 KB
/// against level 1's 25.7 KB and level 19's 17.3 KB, at 5 ms a frame (level 19: 260 ms); with the two cameras
/// encoded on two threads a 60 Hz pair is still written faster than real time.
const ZSTD_LEVEL: i32 = 6;

/// A frame image encoded for its file: a plain PGM or a Zstandard-compressed one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EncodedImage {
    /// Whether `bytes` are Zstandard-compressed (`.pgm.zst`) rather than a plain PGM (`.pgm`).
    pub compressed: bool,
    /// The file's bytes.
    pub bytes: Vec<u8>,
}

impl EncodedImage {
    /// The file name of frame `index`'s image in this encoding.
    pub fn file_name(&self, index: u64) -> String {
        if self.compressed {
            crate::compressed_image_file_name(index)
        } else {
            crate::image_file_name(index)
        }
    }
}

/// Encodes frame after frame with one compression context (a Zstandard context at level 6 is a few MB to set
/// up, more than compressing a dark frame).
pub struct ImageEncoder {
    compressor: Option<zstd::bulk::Compressor<'static>>,
}

impl ImageEncoder {
    /// An encoder writing compressed (`compress`) or plain PGM files.
    pub fn new(compress: bool) -> std::io::Result<Self> {
        Ok(ImageEncoder {
            compressor: compress
                .then(|| zstd::bulk::Compressor::new(ZSTD_LEVEL))
                .transpose()?,
        })
    }

    /// Encodes one image; the bytes are sized to the file, not to the compressor's worst case.
    pub fn encode(&mut self, img: &GrayImage) -> std::io::Result<EncodedImage> {
        let pgm = img.to_pgm();
        Ok(match &mut self.compressor {
            Some(c) => {
                let mut bytes = c.compress(&pgm)?;
                bytes.shrink_to_fit();
                EncodedImage {
                    compressed: true,
                    bytes,
                }
            }
            None => EncodedImage {
                compressed: false,
                bytes: pgm,
            },
        })
    }
}

/// An 8-bit grey image, row-major, no padding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GrayImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` bytes, row after row.
    pub data: Vec<u8>,
}

impl GrayImage {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        GrayImage {
            width,
            height,
            data: vec![0; width as usize * height as usize],
        }
    }

    /// The PGM encoding: header `P5\n{w} {h}\n255\n` then the pixels.
    pub fn to_pgm(&self) -> Vec<u8> {
        let header = format!("P5\n{} {}\n255\n", self.width, self.height);
        let mut out = Vec::with_capacity(header.len() + self.data.len());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(&self.data);
        out
    }

    /// The compressed encoding: [`GrayImage::to_pgm`] inside one Zstandard frame (fails only if the compressor
    /// cannot allocate).
    pub fn to_pgm_zst(&self) -> std::io::Result<Vec<u8>> {
        Ok(ImageEncoder::new(true)?.encode(self)?.bytes)
    }

    /// Parses a stored image: a Zstandard-compressed PGM when `path` ends in `.zst`, else a plain PGM. At most
    /// `max_pixels` pixels are decompressed (the calibrated size), so a corrupt or hostile file cannot make the
    /// reader allocate more. `path` names the source in errors.
    pub fn from_stored(bytes: &[u8], path: &Path, max_pixels: usize) -> Result<Self, RecordError> {
        let compressed = path
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.ends_with(ZSTD_SUFFIX));
        if !compressed {
            return Self::from_pgm(bytes, path);
        }
        // Room for the longest header this writer or any sane one produces.
        let capacity = max_pixels.saturating_add(64);
        let pgm = zstd::bulk::decompress(bytes, capacity).map_err(|e| RecordError::BadImage {
            path: path.to_path_buf(),
            reason: format!("not a Zstandard-compressed PGM of at most {max_pixels} pixels: {e}"),
        })?;
        Self::from_pgm(&pgm, path)
    }

    /// Parses a binary PGM (`P5`, maxval 255; comments allowed in the header). `path` names the source in errors.
    pub fn from_pgm(bytes: &[u8], path: &Path) -> Result<Self, RecordError> {
        let bad = |reason: &str| RecordError::BadImage {
            path: path.to_path_buf(),
            reason: reason.to_string(),
        };
        let mut pos = 0usize;
        let mut fields = [0u64; 3];
        if bytes.get(0..2) != Some(b"P5") {
            return Err(bad("missing P5 magic"));
        }
        pos += 2;
        for field in fields.iter_mut() {
            // Skip whitespace and comments.
            loop {
                match bytes.get(pos) {
                    Some(b) if b.is_ascii_whitespace() => pos += 1,
                    Some(b'#') => {
                        while bytes.get(pos).is_some_and(|&b| b != b'\n') {
                            pos += 1;
                        }
                    }
                    Some(_) => break,
                    None => return Err(bad("header ends early")),
                }
            }
            let start = pos;
            while bytes.get(pos).is_some_and(u8::is_ascii_digit) {
                pos += 1;
            }
            if start == pos || pos - start > 9 {
                return Err(bad("header field is not a number"));
            }
            let text = std::str::from_utf8(&bytes[start..pos]).map_err(|_| bad("header"))?;
            *field = text
                .parse()
                .map_err(|_| bad("header field is not a number"))?;
        }
        if !bytes.get(pos).is_some_and(u8::is_ascii_whitespace) {
            return Err(bad("no whitespace after maxval"));
        }
        pos += 1;
        let [w, h, maxval] = fields;
        if maxval != 255 {
            return Err(bad("maxval must be 255 (8-bit)"));
        }
        let n = w.checked_mul(h).ok_or_else(|| bad("size overflows"))?;
        let data = &bytes[pos..];
        if data.len() as u64 != n {
            return Err(RecordError::BadImage {
                path: path.to_path_buf(),
                reason: format!("expected {n} pixel bytes, found {}", data.len()),
            });
        }
        Ok(GrayImage {
            width: u32::try_from(w).map_err(|_| bad("width too large"))?,
            height: u32::try_from(h).map_err(|_| bad("height too large"))?,
            data: data.to_vec(),
        })
    }
}
