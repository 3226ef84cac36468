//! MATLAB MAT-files, level 5 (MathWorks' "MAT-File Format"; MATLAB's `-v6` and `-v7`, which is level 5 with
//! compressed elements) and version 7.3 (HDF5, read by the submodule `v73`): [`read_mat`] reads every numeric
//! 2-D real matrix of a file, [`write_mat_v5`], [`write_mat`] and [`write_mat_v73`] write matrices (for tests,
//! examples and fuzz seeds). docs/formats.md#mat-files says what is read, what is skipped and what is refused.
//!
//! The layout: a 128-byte header (116 bytes of text starting `MATLAB 5.0 MAT-file`, an 8-byte subsystem offset,
//! the version 0x0100 and the endian indicator, the bytes `IM` in a little-endian file and `MI` in a big-endian
//! one), then data elements. Each element has an 8-byte tag (type u32, size u32, in the file's byte order) and
//! its data padded to 8 bytes; a small element (the size in the upper 16 bits of the tag's first word, at most 4
//! bytes) keeps its data in the tag's second word. A variable is an miMATRIX element (array flags, dimensions,
//! name, real part, imaginary part when complex) or an miCOMPRESSED element whose zlib stream inflates to one.
//!
//! Nothing here allocates from a size read in the file before checking it against the bytes that are there
//! (a compressed element's inflated size against what is left of [`MAX_MAT_VALUE_BYTES`] and deflate's largest ratio), and
//! nothing panics on bad input: every refusal is an [`InputError`] naming the file, the byte and the reason.

use std::io::{Read as _, Write as _};

use crate::io::error::InputError;

mod v73;
pub use v73::write_mat_v73;

/// The most a MAT-file may hold, bytes, counted across all its variables as their values in f64 (8 bytes each,
/// whatever their stored width: int8 data count eight times their size): 512 MiB, 64 million values (three hours
/// of six channels at 1 kHz). Checked before a compressed element is inflated (it may inflate to at most what is
/// left) and before its values are converted; a file beyond it is refused.
pub const MAX_MAT_VALUE_BYTES: usize = 512 << 20;

/// What is left of [`MAX_MAT_VALUE_BYTES`] while a MAT-file is read.
pub(super) struct ValueBudget {
    /// Bytes left.
    pub left: usize,
}

impl ValueBudget {
    /// A whole budget.
    pub fn new() -> ValueBudget {
        ValueBudget { left: MAX_MAT_VALUE_BYTES }
    }

    /// Takes `count` values (as f64) from the budget, or refuses them.
    pub fn take(&mut self, count: u64) -> Result<(), String> {
        let bytes = count.saturating_mul(8);
        if bytes > self.left as u64 {
            return Err(format!(
                "{count} values, {} MB as f64, more than the {} MB left of the {} MB sinscal reads from one MAT-file \
                 (or the MAT-files of one import)",
                bytes >> 20,
                self.left >> 20,
                MAX_MAT_VALUE_BYTES >> 20
            ));
        }
        self.left -= bytes as usize;
        Ok(())
    }
}

/// Bytes of the header of a level-5 MAT-file.
const HEADER_BYTES: usize = 128;
/// Bytes of the header's descriptive text.
const HEADER_TEXT_BYTES: usize = 116;
/// The text a level-5 header starts with (version 7 files too: they are level 5).
const V5_TEXT: &[u8] = b"MATLAB 5.0 MAT-file";
/// The text a version 7.3 header starts with (an HDF5 file with a MATLAB header in its user block).
const V73_TEXT: &[u8] = b"MATLAB 7.3 MAT-file";
/// The HDF5 signature, found at offset 512 of a version 7.3 file (0 for a plain HDF5 file).
const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";
/// Where a version 7.3 file has its HDF5 signature (after MATLAB's 512-byte user block).
const HDF5_SIGNATURE_OFFSET: usize = 512;
/// Deflate's largest expansion: a zlib stream of n bytes inflates to at most about 1032 n bytes.
const MAX_DEFLATE_RATIO: usize = 1032;
/// What the refusals of other versions tell the user to do.
const SAVE_V7_HINT: &str = "in MATLAB, save(FILE, VARIABLES, '-v7') writes a version 7 MAT-file, which sinscal reads";

// Data types of element tags.
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

// Array classes (the low byte of the array flags) and flags.
const MX_DOUBLE_CLASS: u8 = 6;
const MX_UINT64_CLASS: u8 = 15;
const MX_OPAQUE_CLASS: u8 = 17;
const COMPLEX_FLAG: u32 = 0x0800;

/// A matrix to write: its name, rows, columns and column-major values.
pub type NamedMatrix<'a> = (&'a str, usize, usize, &'a [f64]);

/// The byte order of a MAT-file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ByteOrder {
    /// Little-endian: the header ends with the bytes `IM` (what MATLAB writes on every current platform).
    Little,
    /// Big-endian: the header ends with the bytes `MI`.
    Big,
}

/// One numeric 2-D real matrix of a MAT-file, its values converted to f64.
#[derive(Clone, Debug, PartialEq)]
pub struct MatMatrix {
    /// The variable's name.
    pub name: String,
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    /// The values, column-major as MATLAB stores them: `data[col * rows + row]`; `rows * cols` of them.
    pub data: Vec<f64>,
}

impl MatMatrix {
    /// The value at `row`, `col` (0-based), `None` outside the matrix.
    pub fn get(&self, row: usize, col: usize) -> Option<f64> {
        if row < self.rows && col < self.cols {
            self.data.get(col * self.rows + row).copied()
        } else {
            None
        }
    }

    /// Column `col` (0-based), `None` outside the matrix.
    pub fn column(&self, col: usize) -> Option<&[f64]> {
        if col < self.cols {
            self.data.get(col * self.rows..(col + 1) * self.rows)
        } else {
            None
        }
    }
}

/// Every numeric 2-D real matrix of a level-5 MAT-file (the header text `MATLAB 5.0 MAT-file`; MATLAB's
/// `-v6` and `-v7` files, compressed or not, either byte order), in file order, or of a version 7.3 MAT-file
/// (the header text `MATLAB 7.3 MAT-file`, HDF5 from byte 512; `-v7.3`), in the order of its root group (by
/// name in MATLAB's files: the submodule `v73` says how the variables are found and transposed). Numeric means the classes
/// double, single and the eight integer classes (a logical array is uint8 and reads as 0 and 1); the values
/// of every storage type are converted to f64 (64-bit integers beyond 2^53 round to the nearest f64).
/// Other variables (char arrays, cells, structs, sparse and complex arrays, N-d arrays, objects, the unnamed
/// subsystem data) are skipped, and named in the refusal when no matrix is left.
///
/// Refused with a reason (`source` names the file in it): a file that is not a MAT-file (text, a version 4
/// file and an HDF5 file without MATLAB's header are named as such), HDF5 data that do not read, a dataset
/// larger than the file can hold, an element cut short or larger than the bytes
/// left, a compressed element that does not inflate, values beyond [`MAX_MAT_VALUE_BYTES`], dimensions
/// whose product overflows or disagrees with the number of values, and a NaN or infinite value (named by its
/// variable, row and column: sinscal reads finite values only).
pub fn read_mat(bytes: &[u8], source: &str) -> Result<Vec<MatMatrix>, InputError> {
    read_mat_within(bytes, source, &mut ValueBudget::new())
}

/// [`read_mat`] with the values taken from `budget`: the MAT-files of one import share one
/// [`MAX_MAT_VALUE_BYTES`].
pub(super) fn read_mat_within(
    bytes: &[u8],
    source: &str,
    budget: &mut ValueBudget,
) -> Result<Vec<MatMatrix>, InputError> {
    if bytes.starts_with(V73_TEXT) {
        if bytes.get(HDF5_SIGNATURE_OFFSET..HDF5_SIGNATURE_OFFSET + 8) != Some(HDF5_SIGNATURE) {
            let reason = format!(
                "a MATLAB 7.3 header without the HDF5 signature at byte {HDF5_SIGNATURE_OFFSET}: the file is cut \
                 short or not a MAT-file ({} bytes)",
                bytes.len()
            );
            return Err(InputError::file(source, reason));
        }
        let variables =
            v73::read_variables(bytes, budget).map_err(|r| InputError::file(source, format!("MATLAB 7.3: {r}")))?;
        return matrices_or_refused(variables, source);
    }
    let order = header_byte_order(bytes).map_err(|reason| InputError::file(source, reason))?;
    let mut variables = Vec::new();
    let mut cursor = Cursor { bytes, pos: HEADER_BYTES, order };
    while cursor.pos < bytes.len() {
        let at = cursor.pos;
        if bytes[at..].len() < 8 && bytes[at..].iter().all(|&b| b == 0) {
            break; // the last element's padding
        }
        let element = top_level_element(&mut cursor, budget)
            .map_err(|reason| InputError::file(source, format!("element at byte {at}: {reason}")))?;
        variables.push(element);
    }
    matrices_or_refused(variables, source)
}

/// The matrices among `variables`; refused when there is none, naming what was skipped.
fn matrices_or_refused(variables: Vec<Variable>, source: &str) -> Result<Vec<MatMatrix>, InputError> {
    let mut matrices = Vec::new();
    let mut skipped = Vec::new();
    for v in variables {
        match v {
            Variable::Matrix(m) => matrices.push(m),
            Variable::Skipped(what) => skipped.push(what),
        }
    }
    if matrices.is_empty() {
        let reason = if skipped.is_empty() {
            "no variables: the MAT-file has a header only".to_string()
        } else {
            format!("no numeric 2-D real matrix; the file holds {}", skipped.join(", "))
        };
        return Err(InputError::file(source, reason));
    }
    Ok(matrices)
}

/// A MAT-file (level 5, little-endian) holding `matrices` (name, rows, cols, column-major values) as
/// uncompressed miDOUBLE arrays of class double, in that order.
///
/// Refused (the writer checks what it writes): a name that MATLAB cannot load (empty, longer than 63 bytes,
/// not a letter followed by letters, digits and underscores), a name given twice, a value count other than
/// `rows * cols`, a NaN or infinite value (which [`read_mat`] refuses), a matrix too large for a level-5
/// element (its data beyond 4 GiB).
pub fn write_mat_v5(matrices: &[NamedMatrix<'_>]) -> Result<Vec<u8>, String> {
    write_mat(matrices, ByteOrder::Little, false)
}

/// [`write_mat_v5`] in either byte order, each variable compressed (an miCOMPRESSED element, as MATLAB's
/// default `-v7` writes) when `compress` is set.
pub fn write_mat(matrices: &[NamedMatrix<'_>], order: ByteOrder, compress: bool) -> Result<Vec<u8>, String> {
    let mut names: Vec<&str> = Vec::with_capacity(matrices.len());
    let mut file = header(order);
    for &(name, rows, cols, values) in matrices {
        check_matrix(name, rows, cols, values)?;
        if names.contains(&name) {
            return Err(format!("the variable name '{name}' is given twice"));
        }
        names.push(name);
        let mut real = Vec::with_capacity(values.len() * 8);
        for v in values {
            real.extend_from_slice(&match order {
                ByteOrder::Little => v.to_le_bytes(),
                ByteOrder::Big => v.to_be_bytes(),
            });
        }
        let element = matrix_element(name, [rows, cols], MX_DOUBLE_CLASS, MI_DOUBLE, &real, order)?;
        if compress {
            file.extend(compressed_element(&element, order)?);
        } else {
            file.extend(element);
        }
    }
    Ok(file)
}

/// The checks of [`write_mat_v5`] on one matrix.
fn check_matrix(name: &str, rows: usize, cols: usize, values: &[f64]) -> Result<(), String> {
    let mut chars = name.chars();
    let first_ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic());
    if !first_ok || name.len() > 63 || !chars.all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!(
            "'{name}' is not a MATLAB variable name (a letter, then at most 62 letters, digits or underscores)"
        ));
    }
    if rows.checked_mul(cols) != Some(values.len()) {
        return Err(format!(
            "'{name}': {rows}x{cols} needs {} values, {} given",
            rows as u128 * cols as u128,
            values.len()
        ));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let (row, col) = (i % rows.max(1), i / rows.max(1));
        return Err(format!("'{name}': the value at row {}, column {} is {}", row + 1, col + 1, values[i]));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------------
// Reading

/// What a variable turned out to be.
enum Variable {
    /// A numeric 2-D real matrix.
    Matrix(MatMatrix),
    /// Another variable, described for the refusal of a file without a matrix ("'s' (struct)").
    Skipped(String),
}

/// A position in a buffer of elements (the file, or an inflated element, or an miMATRIX's contents).
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    order: ByteOrder,
}

/// One element: its type and its data.
struct Element<'a> {
    ty: u32,
    data: &'a [u8],
}

impl<'a> Cursor<'a> {
    fn u32_at(&self, at: usize) -> Option<u32> {
        let b: [u8; 4] = self.bytes.get(at..at.checked_add(4)?)?.try_into().ok()?;
        Some(match self.order {
            ByteOrder::Little => u32::from_le_bytes(b),
            ByteOrder::Big => u32::from_be_bytes(b),
        })
    }

    /// The next element; the cursor moves past it, past its padding to 8 bytes when `padded` (and the
    /// padding is there: the last element of a buffer may end without it).
    fn element(&mut self, padded: bool) -> Result<Element<'a>, String> {
        let left = self.bytes.len() - self.pos;
        let (Some(first), Some(second)) = (self.u32_at(self.pos), self.u32_at(self.pos + 4)) else {
            return Err(format!("truncated: {left} bytes left, a tag has 8"));
        };
        if first >> 16 != 0 {
            // A small element: the type in the lower 16 bits, the size in the upper ones, the data in the
            // tag's second word.
            let (ty, size) = (first & 0xffff, (first >> 16) as usize);
            if size > 4 {
                return Err(format!("a small element (type {ty}) of {size} bytes: it holds at most 4"));
            }
            let data = &self.bytes[self.pos + 4..self.pos + 4 + size];
            self.pos += 8;
            return Ok(Element { ty, data });
        }
        let (start, size) = (self.pos + 8, second as usize);
        if size > left - 8 {
            return Err(format!("an element of type {first} says it has {size} bytes, only {} are left", left - 8));
        }
        let data = &self.bytes[start..start + size];
        let end = if padded { start + size.div_ceil(8) * 8 } else { start + size };
        self.pos = end.min(self.bytes.len());
        Ok(Element { ty: first, data })
    }

    /// The next element, which must be of type `ty` (`what` names it in the refusal).
    fn expect(&mut self, ty: u32, what: &str) -> Result<&'a [u8], String> {
        let at = self.pos;
        let e = self.element(true).map_err(|r| format!("{what} at byte {at}: {r}"))?;
        if e.ty != ty {
            return Err(format!("{what} at byte {at} has type {}, expected {ty}", e.ty));
        }
        Ok(e.data)
    }
}

/// One variable at the top level of the file: an miMATRIX, or an miCOMPRESSED element holding one.
fn top_level_element(cursor: &mut Cursor<'_>, budget: &mut ValueBudget) -> Result<Variable, String> {
    // A compressed element is not padded (MATLAB starts the next element right after it).
    let padded = cursor.u32_at(cursor.pos) != Some(MI_COMPRESSED);
    let element = cursor.element(padded)?;
    match element.ty {
        MI_MATRIX => variable(element.data, cursor.order, budget),
        MI_COMPRESSED => {
            let inflated = inflate(element.data, budget.left)?;
            let mut inner = Cursor { bytes: &inflated, pos: 0, order: cursor.order };
            let content = inner.expect(MI_MATRIX, "the inflated element")?;
            // Byte positions from here on are those of the inflated data.
            variable(content, cursor.order, budget).map_err(|r| format!("compressed, in its inflated data: {r}"))
        }
        ty => Err(format!("type {ty} at the top level: a MAT-file's variables are miMATRIX (14) or miCOMPRESSED (15)")),
    }
}

/// The zlib stream of an miCOMPRESSED element, inflated; refused beyond `limit` bytes (what is left of
/// [`MAX_MAT_VALUE_BYTES`]).
/// The buffer grows with what the stream gives, from a first guess bounded by deflate's largest ratio.
fn inflate(compressed: &[u8], limit: usize) -> Result<Vec<u8>, String> {
    let mut decoder = flate2::read::ZlibDecoder::new(compressed);
    let mut head = [0u8; 8];
    decoder.read_exact(&mut head).map_err(|e| format!("the zlib stream does not inflate to a tag: {e}"))?;
    // The inflated tag's size, either byte order (only a guess for the buffer, checked by the reading).
    let size = u32::from_le_bytes([head[4], head[5], head[6], head[7]])
        .min(u32::from_be_bytes([head[4], head[5], head[6], head[7]])) as usize;
    // At most the limit and one byte (what the refusal needs to see): never a doubling past the limit.
    let bound = compressed.len().saturating_mul(MAX_DEFLATE_RATIO).min(limit.saturating_add(1));
    let mut out = Vec::with_capacity(size.saturating_add(8).min(bound));
    out.extend_from_slice(&head);
    let rest = limit.saturating_add(1).saturating_sub(head.len()) as u64;
    decoder.take(rest).read_to_end(&mut out).map_err(|e| format!("the zlib stream does not inflate: {e}"))?;
    if out.len() > limit {
        return Err(format!(
            "it inflates to more than {limit} bytes, what is left of the {} MB sinscal reads from one MAT-file",
            MAX_MAT_VALUE_BYTES >> 20
        ));
    }
    Ok(out)
}

/// The contents of an miMATRIX element: a numeric 2-D real matrix, or a skipped variable described.
fn variable(content: &[u8], order: ByteOrder, budget: &mut ValueBudget) -> Result<Variable, String> {
    let mut c = Cursor { bytes: content, pos: 0, order };
    if content.is_empty() {
        return Ok(Variable::Skipped("an empty miMATRIX element".to_string()));
    }
    let flags = c.expect(MI_UINT32, "the array flags")?;
    let flags = Cursor { bytes: flags, pos: 0, order }.u32_at(0).ok_or("the array flags have fewer than 4 bytes")?;
    let class = (flags & 0xff) as u8;
    if class == MX_OPAQUE_CLASS {
        // An object (MATLAB's classes: string, table, datetime, ...): no dimensions, the name comes next.
        let name = c.expect(MI_INT8, "the name").map(|n| String::from_utf8_lossy(n).into_owned())?;
        return Ok(Variable::Skipped(format!("'{name}' (an object)")));
    }
    let dims_bytes = c.expect(MI_INT32, "the dimensions")?;
    let name = String::from_utf8_lossy(c.expect(MI_INT8, "the name")?).into_owned();
    let dims = dimensions(dims_bytes, order).map_err(|r| format!("'{name}': {r}"))?;
    let shape = dims.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("x");
    let skip = |why: &str| Ok(Variable::Skipped(format!("'{name}' ({why})")));
    if name.is_empty() {
        return Ok(Variable::Skipped("an unnamed variable (MATLAB's subsystem data)".to_string()));
    }
    if !(MX_DOUBLE_CLASS..=MX_UINT64_CLASS).contains(&class) {
        return skip(class_name(class));
    }
    if flags & COMPLEX_FLAG != 0 {
        return skip(&format!("complex {shape}"));
    }
    let &[rows, cols] = dims.as_slice() else {
        return skip(&format!("{}-d {shape}", dims.len()));
    };
    let count = rows.checked_mul(cols).ok_or_else(|| format!("'{name}': the dimensions {shape} overflow"))?;
    budget.take(count as u64).map_err(|r| format!("'{name}' ({shape}): {r}"))?;
    let at = c.pos;
    let real = c.element(true).map_err(|r| format!("'{name}': the real part at byte {at}: {r}"))?;
    let data = values(real.ty, real.data, order, count).map_err(|r| format!("'{name}' ({shape}): {r}"))?;
    finite_or_refused(&name, rows, &data)?;
    Ok(Variable::Matrix(MatMatrix { name, rows, cols, data }))
}

/// Refuses the first NaN or infinite value of a matrix of `rows` rows (column-major `data`), by place.
fn finite_or_refused(name: &str, rows: usize, data: &[f64]) -> Result<(), String> {
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        let (row, col) = (i % rows.max(1), i / rows.max(1));
        return Err(format!(
            "'{name}': the value at row {}, column {} is {}: sinscal reads finite values only",
            row + 1,
            col + 1,
            data[i]
        ));
    }
    Ok(())
}

/// The dimensions of an array: at least two, none negative.
fn dimensions(bytes: &[u8], order: ByteOrder) -> Result<Vec<usize>, String> {
    if !bytes.len().is_multiple_of(4) || bytes.len() < 8 {
        return Err(format!("dimensions of {} bytes: at least two 4-byte integers are needed", bytes.len()));
    }
    let c = Cursor { bytes, pos: 0, order };
    (0..bytes.len() / 4)
        .map(|i| {
            let d = c.u32_at(4 * i).unwrap_or(0) as i32;
            usize::try_from(d).map_err(|_| format!("dimension {} is {d}: negative", i + 1))
        })
        .collect()
}

/// The name of a class that is skipped.
fn class_name(class: u8) -> &'static str {
    match class {
        1 => "cell array",
        2 => "struct",
        3 => "object",
        4 => "char array",
        5 => "sparse array",
        16 => "function handle",
        _ => "unknown class",
    }
}

/// `count` values of storage type `ty` as f64: the data must hold exactly `count` of them.
fn values(ty: u32, bytes: &[u8], order: ByteOrder, count: usize) -> Result<Vec<f64>, String> {
    let width = match ty {
        MI_INT8 | MI_UINT8 => 1,
        MI_INT16 | MI_UINT16 => 2,
        MI_INT32 | MI_UINT32 | MI_SINGLE => 4,
        MI_DOUBLE | MI_INT64 | MI_UINT64 => 8,
        _ => return Err(format!("the real part has type {ty}, not a numeric type")),
    };
    if !bytes.len().is_multiple_of(width) || bytes.len() / width != count {
        return Err(format!(
            "the dimensions give {count} values, the real part holds {} bytes ({} values of {width} bytes)",
            bytes.len(),
            bytes.len() as f64 / width as f64
        ));
    }
    // `count` values are there (checked above): the allocation is bounded by the input.
    let mut out = Vec::with_capacity(count);
    let big = order == ByteOrder::Big;
    match ty {
        MI_INT8 => out.extend(bytes.iter().map(|&b| b as i8 as f64)),
        MI_UINT8 => out.extend(bytes.iter().map(|&b| b as f64)),
        MI_INT16 => decode(bytes, big, &mut out, |b: [u8; 2]| i16::from_le_bytes(b) as f64),
        MI_UINT16 => decode(bytes, big, &mut out, |b: [u8; 2]| u16::from_le_bytes(b) as f64),
        MI_INT32 => decode(bytes, big, &mut out, |b: [u8; 4]| i32::from_le_bytes(b) as f64),
        MI_UINT32 => decode(bytes, big, &mut out, |b: [u8; 4]| u32::from_le_bytes(b) as f64),
        MI_SINGLE => decode(bytes, big, &mut out, |b: [u8; 4]| f32::from_le_bytes(b) as f64),
        MI_INT64 => decode(bytes, big, &mut out, |b: [u8; 8]| i64::from_le_bytes(b) as f64),
        MI_UINT64 => decode(bytes, big, &mut out, |b: [u8; 8]| u64::from_le_bytes(b) as f64),
        _ => decode(bytes, big, &mut out, f64::from_le_bytes),
    }
    Ok(out)
}

/// Each `N`-byte value of `bytes` (byte-swapped first when `big`) through `f` into `out`.
fn decode<const N: usize>(bytes: &[u8], big: bool, out: &mut Vec<f64>, f: impl Fn([u8; N]) -> f64) {
    for chunk in bytes.chunks_exact(N) {
        let mut b = [0u8; N];
        b.copy_from_slice(chunk);
        if big {
            b.reverse();
        }
        out.push(f(b));
    }
}

/// The byte order of a level-5 MAT-file from its header; the refusal names what the bytes are instead
/// (text, a version 4 MAT-file, HDF5 without MATLAB's header, a cut header).
fn header_byte_order(bytes: &[u8]) -> Result<ByteOrder, String> {
    if bytes.is_empty() {
        return Err("an empty file, not a MAT-file".to_string());
    }
    let hdf5_at_512 = bytes.get(HDF5_SIGNATURE_OFFSET..HDF5_SIGNATURE_OFFSET + 8) == Some(HDF5_SIGNATURE);
    if hdf5_at_512 || bytes.starts_with(HDF5_SIGNATURE) {
        return Err("an HDF5 file without MATLAB's header (a version 7.3 MAT-file starts with the text 'MATLAB 7.3 \
             MAT-file'): not a MAT-file"
            .to_string());
    }
    if bytes.starts_with(V5_TEXT) {
        let Some(tail) = bytes.get(HEADER_TEXT_BYTES + 8..HEADER_BYTES) else {
            return Err(format!("truncated: {} bytes, a MAT-file's header has {HEADER_BYTES}", bytes.len()));
        };
        let (order, version) = match &tail[2..4] {
            b"IM" => (ByteOrder::Little, u16::from_le_bytes([tail[0], tail[1]])),
            b"MI" => (ByteOrder::Big, u16::from_be_bytes([tail[0], tail[1]])),
            other => {
                return Err(format!(
                    "the header's endian indicator is {:?}, not \"IM\" or \"MI\"",
                    String::from_utf8_lossy(other)
                ))
            }
        };
        if version != 0x0100 {
            return Err(format!("the header's version is 0x{version:04x}; a level-5 MAT-file has 0x0100"));
        }
        return Ok(order);
    }
    if looks_like_v4(bytes) {
        return Err(format!(
            "a version 4 MAT-file (MATLAB 4 format: no 128-byte text header): sinscal reads level-5 MAT-files \
             (versions 6 and 7) and version 7.3; {SAVE_V7_HINT}"
        ));
    }
    let head = &bytes[..bytes.len().min(512)];
    if head.iter().all(|&b| b.is_ascii_graphic() || b" \t\r\n".contains(&b)) {
        let first = String::from_utf8_lossy(head.split(|&b| b == b'\n').next().unwrap_or_default()).into_owned();
        let first = first.trim_end();
        let first = if first.len() > 60 { format!("{}...", &first[..60]) } else { first.to_string() };
        return Err(format!(
            "text, not a MAT-file (its first line: '{first}'): a MAT-file starts with the 128-byte header \
             'MATLAB 5.0 MAT-file'; text matrices (MATLAB's save -ascii, imu_tk's .mat files) are read by the \
             importer of their format, such as `sinscal import imutk`"
        ));
    }
    Err("not a MAT-file: it does not start with the header text 'MATLAB 5.0 MAT-file'".to_string())
}

/// Whether `bytes` start with a version 4 matrix header: five 32-bit integers (type MOPT, rows, columns,
/// imaginary flag, name length) in either byte order, then the name ending with a NUL byte.
fn looks_like_v4(bytes: &[u8]) -> bool {
    [ByteOrder::Little, ByteOrder::Big].into_iter().any(|order| {
        let c = Cursor { bytes, pos: 0, order };
        let words: Option<Vec<u32>> = (0..5).map(|i| c.u32_at(4 * i)).collect();
        let Some(&[mopt, rows, cols, imagf, namlen]) = words.as_deref() else { return false };
        // M: 0 little-endian IEEE, 1 big-endian IEEE; O: 0; P: 0..=5 (the storage type); T: 0..=2.
        let m_ok = mopt / 1000 == if order == ByteOrder::Little { 0 } else { 1 };
        let mopt_ok = m_ok && (mopt / 100) % 10 == 0 && (mopt / 10) % 10 <= 5 && mopt % 10 <= 2;
        let sizes_ok = rows < 1 << 31 && cols < 1 << 31 && imagf <= 1 && (1..=64).contains(&namlen);
        mopt_ok && sizes_ok && bytes.get(20 + namlen as usize - 1) == Some(&0)
    })
}

// ---------------------------------------------------------------------------------------------------------------
// Writing

/// The 128-byte header: the text, a zero subsystem offset, the version and the endian indicator.
fn header(order: ByteOrder) -> Vec<u8> {
    let mut h = b"MATLAB 5.0 MAT-file, written by sinscal".to_vec();
    h.resize(HEADER_TEXT_BYTES, b' ');
    h.extend_from_slice(&[0; 8]);
    match order {
        ByteOrder::Little => h.extend_from_slice(&[0x00, 0x01, b'I', b'M']),
        ByteOrder::Big => h.extend_from_slice(&[0x01, 0x00, b'M', b'I']),
    }
    h
}

/// A tag and its data, padded to 8 bytes; data of 1 to 4 bytes as a small element (as MATLAB writes short
/// names).
fn push_element(out: &mut Vec<u8>, ty: u32, data: &[u8], order: ByteOrder) -> Result<(), String> {
    let size = u32::try_from(data.len())
        .map_err(|_| format!("an element of {} bytes: a level-5 element has at most 4 GiB", data.len()))?;
    let word = |v: u32| match order {
        ByteOrder::Little => v.to_le_bytes(),
        ByteOrder::Big => v.to_be_bytes(),
    };
    if (1..=4).contains(&size) {
        out.extend_from_slice(&word(size << 16 | ty));
        out.extend_from_slice(data);
        out.resize(out.len() + 4 - data.len(), 0);
        return Ok(());
    }
    out.extend_from_slice(&word(ty));
    out.extend_from_slice(&word(size));
    out.extend_from_slice(data);
    out.resize(out.len() + (8 - data.len() % 8) % 8, 0);
    Ok(())
}

/// An miMATRIX element: array flags (`class`, real), the dimensions, the name, and the real part stored as
/// `storage` (a data type) with the bytes `real` (already in the file's byte order).
fn matrix_element(
    name: &str,
    dims: [usize; 2],
    class: u8,
    storage: u32,
    real: &[u8],
    order: ByteOrder,
) -> Result<Vec<u8>, String> {
    let word = |v: u32| match order {
        ByteOrder::Little => v.to_le_bytes(),
        ByteOrder::Big => v.to_be_bytes(),
    };
    let mut content = Vec::with_capacity(real.len() + 64 + name.len());
    push_element(&mut content, MI_UINT32, &[word(class as u32), word(0)].concat(), order)?;
    let mut dim_bytes = Vec::new();
    for d in dims {
        let d =
            i32::try_from(d).map_err(|_| format!("'{name}': dimension {d} does not fit a level-5 file's 32 bits"))?;
        dim_bytes.extend_from_slice(&word(d as u32));
    }
    push_element(&mut content, MI_INT32, &dim_bytes, order)?;
    push_element(&mut content, MI_INT8, name.as_bytes(), order)?;
    push_element(&mut content, storage, real, order)?;
    let mut element = Vec::with_capacity(content.len() + 8);
    push_element(&mut element, MI_MATRIX, &content, order)?;
    Ok(element)
}

/// An miCOMPRESSED element holding `element` (zlib, not padded: as MATLAB writes it).
fn compressed_element(element: &[u8], order: ByteOrder) -> Result<Vec<u8>, String> {
    let mut encoder = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(element).map_err(|e| e.to_string())?;
    let z = encoder.finish().map_err(|e| e.to_string())?;
    let size = u32::try_from(z.len()).map_err(|_| "a compressed element beyond 4 GiB".to_string())?;
    let word = |v: u32| match order {
        ByteOrder::Little => v.to_le_bytes(),
        ByteOrder::Big => v.to_be_bytes(),
    };
    Ok([&word(MI_COMPRESSED)[..], &word(size)[..], &z[..]].concat())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A word in the file's byte order.
    fn word(v: u32, order: ByteOrder) -> [u8; 4] {
        match order {
            ByteOrder::Little => v.to_le_bytes(),
            ByteOrder::Big => v.to_be_bytes(),
        }
    }

    /// A file of the header and `elements`.
    fn file(order: ByteOrder, elements: &[Vec<u8>]) -> Vec<u8> {
        let mut f = header(order);
        for e in elements {
            f.extend_from_slice(e);
        }
        f
    }

    /// An miMATRIX element with the array flags word `flags`, the dimensions `dims` and the parts given as
    /// (storage type, bytes in the file's byte order).
    fn element(name: &str, flags: u32, dims: &[i32], parts: &[(u32, Vec<u8>)], order: ByteOrder) -> Vec<u8> {
        let mut content = Vec::new();
        push_element(&mut content, MI_UINT32, &[word(flags, order), word(0, order)].concat(), order).unwrap();
        let dims: Vec<u8> = dims.iter().flat_map(|&d| word(d as u32, order)).collect();
        push_element(&mut content, MI_INT32, &dims, order).unwrap();
        push_element(&mut content, MI_INT8, name.as_bytes(), order).unwrap();
        for (ty, bytes) in parts {
            push_element(&mut content, *ty, bytes, order).unwrap();
        }
        let mut e = Vec::new();
        push_element(&mut e, MI_MATRIX, &content, order).unwrap();
        e
    }

    fn doubles(values: &[f64], order: ByteOrder) -> Vec<u8> {
        values.iter().flat_map(|v| if order == ByteOrder::Little { v.to_le_bytes() } else { v.to_be_bytes() }).collect()
    }

    fn refusal(bytes: &[u8]) -> String {
        match read_mat(bytes, "test.mat") {
            Ok(m) => panic!("accepted {} matrices, expected a refusal", m.len()),
            Err(e) => e.to_string(),
        }
    }

    fn assert_same(read: &[MatMatrix], written: &[NamedMatrix<'_>]) {
        assert_eq!(read.len(), written.len());
        for (m, &(name, rows, cols, values)) in read.iter().zip(written) {
            assert_eq!((m.name.as_str(), m.rows, m.cols), (name, rows, cols));
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&m.data), bits(values), "{name}: values differ");
        }
    }

    /// Three matrices of every shape kind, with values whose bits are easy to lose (-0, a subnormal, the
    /// extremes).
    fn sample_values() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let one = vec![std::f64::consts::PI];
        let imu: Vec<f64> = (0..21).map(|i| (i as f64 * 0.37).sin() * 10f64.powi(i % 7 - 3)).collect();
        let odd = vec![-0.0, 5e-324, f64::MAX, f64::MIN, f64::MIN_POSITIVE, 1.0 / 3.0];
        (one, imu, odd)
    }

    #[test]
    fn round_trip_keeps_names_shapes_and_bits() {
        let (one, imu, odd) = sample_values();
        let empty: Vec<f64> = Vec::new();
        let written: [NamedMatrix<'_>; 5] = [
            ("a", 1, 1, &one),
            ("imu_3x7", 3, 7, &imu),
            ("odd", 2, 3, &odd),
            ("row", 1, 21, &imu),
            ("nothing", 0, 0, &empty),
        ];
        for order in [ByteOrder::Little, ByteOrder::Big] {
            for compress in [false, true] {
                let bytes = write_mat(&written, order, compress).unwrap();
                let read = read_mat(&bytes, "test.mat").unwrap();
                assert_same(&read, &written);
            }
        }
        let read = read_mat(&write_mat_v5(&written).unwrap(), "test.mat").unwrap();
        assert_eq!(read[1].get(2, 6), Some(imu[20]));
        assert_eq!(read[1].get(1, 0), Some(imu[1]));
        assert_eq!(read[1].get(3, 0), None);
        assert_eq!(read[1].get(0, 7), None);
        assert_eq!(read[1].column(1), Some(&imu[3..6]));
        assert_eq!(read[1].column(7), None);
    }

    #[test]
    fn writer_refuses_what_it_cannot_write_or_sinscal_cannot_read() {
        let v = [1.0, 2.0];
        let cases: [(&[NamedMatrix<'_>], &str); 7] = [
            (&[("", 1, 2, &v)], "not a MATLAB variable name"),
            (&[("1x", 1, 2, &v)], "not a MATLAB variable name"),
            (&[("a b", 1, 2, &v)], "not a MATLAB variable name"),
            (&[(&"n".repeat(64), 1, 2, &v)], "not a MATLAB variable name"),
            (&[("a", 1, 2, &v), ("a", 2, 1, &v)], "given twice"),
            (&[("a", 2, 2, &v)], "2x2 needs 4 values, 2 given"),
            (&[("a", 2, 1, &[1.0, f64::NAN])], "row 2, column 1 is NaN"),
        ];
        for (matrices, reason) in cases {
            let e = write_mat_v5(matrices).unwrap_err();
            assert!(e.contains(reason), "'{e}' does not say '{reason}'");
        }
        assert!(write_mat_v5(&[(&"n".repeat(63), 1, 2, &v)]).is_ok(), "63 bytes is MATLAB's longest name");
    }

    #[test]
    fn compressed_element_reads_back_between_uncompressed_ones() {
        let order = ByteOrder::Little;
        let (one, imu, _) = sample_values();
        let plain = element("gyro", 6, &[3, 7], &[(MI_DOUBLE, doubles(&imu, order))], order);
        // Compressed by hand, as MATLAB's default -v7 does: zlib of the whole miMATRIX element, tag not padded.
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
        z.write_all(&plain).unwrap();
        let z = z.finish().unwrap();
        assert_ne!(z.len() % 8, 0, "the test needs a compressed length that is not a multiple of 8");
        let compressed = [&MI_COMPRESSED.to_le_bytes()[..], &(z.len() as u32).to_le_bytes(), &z].concat();
        let last = element("t", 6, &[1, 1], &[(MI_DOUBLE, doubles(&one, order))], order);
        let bytes = file(order, &[compressed.clone(), last.clone(), compressed]);
        let read = read_mat(&bytes, "test.mat").unwrap();
        assert_same(&read, &[("gyro", 3, 7, &imu), ("t", 1, 1, &one), ("gyro", 3, 7, &imu)]);
    }

    #[test]
    fn big_endian_file_reads_back() {
        let (one, imu, odd) = sample_values();
        let written: [NamedMatrix<'_>; 3] = [("acc", 7, 3, &imu), ("k", 1, 1, &one), ("odd", 3, 2, &odd)];
        for compress in [false, true] {
            let bytes = write_mat(&written, ByteOrder::Big, compress).unwrap();
            assert_eq!(&bytes[124..128], &[1, 0, b'M', b'I']);
            assert_same(&read_mat(&bytes, "test.mat").unwrap(), &written);
        }
    }

    #[test]
    fn every_numeric_storage_type_converts_to_f64() {
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let int16: Vec<u8> =
                [-3i16, 0, 32767, -32768].iter().flat_map(|v| word(*v as u16 as u32, order)[..].to_vec()).collect();
            // word() gives 4 bytes; an int16 is the 2 low-order ones of it.
            let int16: Vec<u8> = int16
                .chunks(4)
                .flat_map(|w| if order == ByteOrder::Little { w[..2].to_vec() } else { w[2..].to_vec() })
                .collect();
            let singles: Vec<u8> = [1.5f32, -0.1].iter().flat_map(|v| word(v.to_bits(), order)).collect();
            let u64s: Vec<u8> = [u64::MAX, 7]
                .iter()
                .flat_map(|v| if order == ByteOrder::Little { v.to_le_bytes() } else { v.to_be_bytes() })
                .collect();
            let elements = [
                // Class double stored as miINT16 and miUINT8 (MATLAB's way of saving space), class single as
                // miSINGLE, int8 as miINT8 in a small element, uint64 as miUINT64, int32 as miINT32.
                element("d16", 6, &[2, 2], &[(MI_INT16, int16)], order),
                element("d8", 6, &[1, 3], &[(MI_UINT8, vec![0, 255, 7])], order),
                element("s", 7, &[2, 1], &[(MI_SINGLE, singles)], order),
                element("i8", 8, &[1, 2], &[(MI_INT8, vec![0x80, 0x7f])], order),
                element("u64", 15, &[2, 1], &[(MI_UINT64, u64s)], order),
                element("i32", 12, &[1, 1], &[(MI_INT32, word(-70000i32 as u32, order).to_vec())], order),
            ];
            let read = read_mat(&file(order, &elements), "test.mat").unwrap();
            let values: Vec<(&str, &[f64])> = read.iter().map(|m| (m.name.as_str(), m.data.as_slice())).collect();
            assert_eq!(
                values,
                [
                    ("d16", &[-3.0, 0.0, 32767.0, -32768.0][..]),
                    ("d8", &[0.0, 255.0, 7.0]),
                    ("s", &[1.5, -0.1f32 as f64]),
                    ("i8", &[-128.0, 127.0]),
                    ("u64", &[u64::MAX as f64, 7.0]),
                    ("i32", &[-70000.0]),
                ],
                "{order:?}"
            );
        }
    }

    #[test]
    fn other_variables_are_skipped_and_named_when_nothing_is_left() {
        let order = ByteOrder::Little;
        let chars: Vec<u8> = "hello".encode_utf16().flat_map(|c| c.to_le_bytes()).collect();
        let label = element("label", 4, &[1, 5], &[(MI_UINT16, chars)], order);
        let e = refusal(&file(order, std::slice::from_ref(&label)));
        assert!(e.contains("no numeric 2-D real matrix") && e.contains("'label' (char array)"), "{e}");
        let complex = element(
            "z",
            COMPLEX_FLAG | 6,
            &[1, 1],
            &[(MI_DOUBLE, doubles(&[1.0], order)), (MI_DOUBLE, doubles(&[2.0], order))],
            order,
        );
        let cube = element("cube", 6, &[2, 1, 2], &[(MI_DOUBLE, doubles(&[1.0; 4], order))], order);
        let cell = element("c", 1, &[1, 1], &[], order);
        let unnamed = element("", 9, &[1, 4], &[(MI_UINT8, vec![1, 2, 3, 4])], order);
        let e = refusal(&file(order, &[label.clone(), complex.clone(), cube.clone(), cell.clone(), unnamed.clone()]));
        for what in ["'z' (complex 1x1)", "'cube' (3-d 2x1x2)", "'c' (cell array)", "unnamed variable"] {
            assert!(e.contains(what), "'{e}' does not name {what}");
        }
        let kept = element("kept", 6, &[1, 2], &[(MI_DOUBLE, doubles(&[4.0, 5.0], order))], order);
        let read = read_mat(&file(order, &[label, complex, kept, cube, cell, unnamed]), "test.mat").unwrap();
        assert_same(&read, &[("kept", 1, 2, &[4.0, 5.0])]);
    }

    #[test]
    fn version_7_3_is_read_and_a_bad_one_refused_with_a_reason() {
        let v73 = write_mat_v73(&[("acc", 3, 2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0])], true).unwrap();
        assert!(v73.starts_with(V73_TEXT));
        let read = read_mat(&v73, "test.mat").unwrap();
        assert_same(&read, &[("acc", 3, 2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0])]);
        let mut garbage = v73[..520].to_vec();
        garbage.resize(2048, 0x5a);
        let e = refusal(&garbage);
        assert!(e.contains("MATLAB 7.3: the HDF5 data do not read"), "{e}");
        let mut header_only =
            b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 .".to_vec();
        header_only.resize(128, b' ');
        assert!(refusal(&header_only).contains("without the HDF5 signature at byte 512"));
        let mut signature_only = vec![0u8; 512];
        signature_only.extend_from_slice(HDF5_SIGNATURE);
        assert!(refusal(&signature_only).contains("an HDF5 file without MATLAB's header"));
    }

    #[test]
    fn version_4_file_is_refused_by_name() {
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let mopt = if order == ByteOrder::Little { 0 } else { 1000 };
            let mut v4: Vec<u8> = [mopt, 2, 1, 0, 2].iter().flat_map(|&w| word(w, order)).collect();
            v4.extend_from_slice(b"x\0");
            v4.extend(doubles(&[1.0, 2.0], order));
            let e = refusal(&v4);
            assert!(e.contains("version 4 MAT-file") && e.contains("'-v7'"), "{e}");
        }
    }

    #[test]
    fn text_and_other_files_are_not_mat_files() {
        let e = refusal(b"   2.9840000e-02   3.3108000e+04   3.3329000e+04\n   3.9857000e-02 1 2\n");
        assert!(e.contains("text, not a MAT-file") && e.contains("2.9840000e-02"), "{e}");
        assert!(refusal(b"").contains("empty file"));
        assert!(refusal(&[0xff, 0xd8, 0xff, 0xe0, 1, 2, 3]).contains("not a MAT-file"));
        let mut bad = write_mat_v5(&[("a", 1, 1, &[1.0])]).unwrap();
        bad[126..128].copy_from_slice(b"XY");
        assert!(refusal(&bad).contains("endian indicator"));
        bad[124..128].copy_from_slice(&[0x00, 0x02, b'I', b'M']);
        assert!(refusal(&bad).contains("version is 0x0200"));
        assert!(refusal(&header(ByteOrder::Little)).contains("no variables"));
    }

    #[test]
    fn every_cut_of_a_file_is_refused() {
        let (one, imu, _) = sample_values();
        for compress in [false, true] {
            let bytes = write_mat(&[("a", 1, 1, &one), ("imu", 3, 7, &imu)], ByteOrder::Little, compress).unwrap();
            for len in 0..bytes.len() {
                match read_mat(&bytes[..len], "test.mat") {
                    // Cut exactly between the variables: the first one is a whole file.
                    Ok(m) => assert_eq!((m.len(), m[0].name.as_str()), (1, "a"), "cut at {len}"),
                    Err(e) => assert!(!e.to_string().is_empty()),
                }
            }
            let cut = refusal(&bytes[..bytes.len() - 9]);
            assert!(cut.contains("only") && cut.contains("left") || cut.contains("inflate"), "{cut}");
        }
    }

    #[test]
    fn sizes_beyond_the_input_are_refused() {
        let order = ByteOrder::Little;
        let mut bytes = write_mat_v5(&[("a", 2, 2, &[1.0, 2.0, 3.0, 4.0])]).unwrap();
        bytes[132..136].copy_from_slice(&0xffff_fff0u32.to_le_bytes());
        let e = refusal(&bytes);
        assert!(e.contains("byte 128") && e.contains("4294967280 bytes, only 80 are left"), "{e}");
        // Inside a compressed element: the inflated tag claims 4 GiB.
        let mut inner = element("a", 6, &[1, 1], &[(MI_DOUBLE, doubles(&[1.0], order))], order);
        inner[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        let z = compressed_element(&inner, order).unwrap();
        assert!(refusal(&file(order, &[z])).contains("4294967295 bytes, only"));
        // Dimensions that disagree with the values, a small element claiming more than 4 bytes.
        let wrong = element("w", 6, &[3, 3], &[(MI_DOUBLE, doubles(&[1.0; 4], order))], order);
        let e = refusal(&file(order, &[wrong]));
        assert!(e.contains("'w' (3x3): the dimensions give 9 values, the real part holds 32 bytes"), "{e}");
        let mut small = write_mat_v5(&[("a", 1, 1, &[1.0])]).unwrap();
        let name_tag = 128 + 8 + 16 + 16;
        assert_eq!(&small[name_tag..name_tag + 5], &[1, 0, 1, 0, b'a'], "the name is a small element");
        small[name_tag + 2] = 9;
        assert!(refusal(&small).contains("small element (type 1) of 9 bytes"));
        let negative = element("n", 6, &[-1, 1], &[(MI_DOUBLE, Vec::new())], order);
        assert!(refusal(&file(order, &[negative])).contains("dimension 1 is -1: negative"));
    }

    #[test]
    fn inflation_is_bounded() {
        let big = vec![0u8; 100_000];
        let z = compressed_element(&big, ByteOrder::Little).unwrap();
        assert!(z.len() < 1000, "zeros compress well ({} bytes)", z.len());
        assert_eq!(inflate(&z[8..], 100_000).map(|v| v.len()), Ok(100_000));
        let e = inflate(&z[8..], 99_999).unwrap_err();
        assert!(e.contains("more than 99999 bytes"), "{e}");
        assert!(inflate(&z[8..z.len() - 4], 100_000).is_err(), "a stream without its checksum");
    }

    #[test]
    fn non_finite_values_are_refused_by_name_and_place() {
        let order = ByteOrder::Big;
        let values = doubles(&[1.0, 2.0, 3.0, f64::NEG_INFINITY], order);
        let e = refusal(&file(order, &[element("acc", 6, &[2, 2], &[(MI_DOUBLE, values)], order)]));
        assert!(e.contains("'acc': the value at row 2, column 2 is -inf: sinscal reads finite values only"), "{e}");
        let nan =
            element("g", 7, &[1, 2], &[(MI_SINGLE, [word(0, order), word(f32::NAN.to_bits(), order)].concat())], order);
        assert!(refusal(&file(order, &[nan])).contains("'g': the value at row 1, column 2 is NaN"));
    }
}
