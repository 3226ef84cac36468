//! MATLAB 7.3 MAT-files: HDF5 files behind MATLAB's 512-byte user block, read with the pure-Rust `hdf5-pure`
//! crate (no C library). docs/formats.md#mat-files says what is read and what is skipped.
//!
//! MATLAB's conventions: every variable is a member of the root group carrying the string attribute
//! `MATLAB_class` ("double", "single", "int8" .. "uint64", "logical", "char", "cell", "struct", ...). An m x n
//! matrix is a dataset of HDF5 shape [n, m]: HDF5's row-major order of that shape is MATLAB's column-major order
//! of the matrix, so the values are read as they are stored, with rows = shape[1] and cols = shape[0]. An empty
//! array is a dataset with the attribute `MATLAB_empty` whose values are its MATLAB dimensions. Complex arrays
//! are compound datasets (real, imag); structs, cells' contents, sparse arrays and objects are groups.

use hdf5_pure::{AttrValue, DType, Dataset, FileBuilder};

use super::{finite_or_refused, MatMatrix, NamedMatrix, ValueBudget, Variable, MAX_DEFLATE_RATIO, MAX_MAT_VALUE_BYTES};

/// Bytes of MATLAB's user block before the HDF5 superblock.
pub const USER_BLOCK_BYTES: usize = 512;
/// The classes read as numeric matrices (a logical array is stored as uint8: 0 and 1).
const NUMERIC_CLASSES: [&str; 11] =
    ["double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "logical"];

/// Every variable of the root group of a version 7.3 MAT-file (`bytes`: the whole file, user block included),
/// in the order the root group lists them (by name in MATLAB's files).
pub(super) fn read_variables(bytes: &[u8], budget: &mut ValueBudget) -> Result<Vec<Variable>, String> {
    let file = hdf5_pure::File::from_bytes(bytes.to_vec()).map_err(|e| format!("the HDF5 data do not read: {e}"))?;
    let root = file.root();
    let names = root.datasets().map_err(|e| format!("the HDF5 root group does not read: {e}"))?;
    let mut variables = Vec::with_capacity(names.len());
    for name in names {
        let dataset = root.dataset(&name).map_err(|e| format!("'{name}': the dataset does not open: {e}"))?;
        variables.push(dataset_variable(&name, &dataset, bytes.len(), budget)?);
    }
    let groups = root.groups().map_err(|e| format!("the HDF5 root group does not read: {e}"))?;
    for name in groups {
        let class = root.group(&name).ok().and_then(|g| g.attrs().ok()).and_then(|a| class_of(&a));
        let what = match class {
            Some(class) => format!("'{name}' ({class})"),
            None => format!("the group '{name}' (MATLAB's internal data)"),
        };
        variables.push(Variable::Skipped(what));
    }
    Ok(variables)
}

/// The `MATLAB_class` attribute of an object's attributes.
fn class_of(attrs: &std::collections::HashMap<String, AttrValue>) -> Option<String> {
    attrs.get("MATLAB_class").and_then(|v| v.as_str()).map(str::to_string)
}

/// Whether an integer attribute is present and non-zero (`MATLAB_empty`).
fn flag_set(attrs: &std::collections::HashMap<String, AttrValue>, key: &str) -> bool {
    match attrs.get(key) {
        Some(AttrValue::U8(v)) => *v != 0,
        Some(AttrValue::U32(v)) => *v != 0,
        Some(AttrValue::I32(v)) => *v != 0,
        Some(AttrValue::U64(v)) => *v != 0,
        Some(AttrValue::I64(v)) => *v != 0,
        Some(_) => true,
        None => false,
    }
}

/// One dataset of the root group: a numeric 2-D real matrix, or a skipped variable described.
fn dataset_variable(
    name: &str,
    dataset: &Dataset,
    file_bytes: usize,
    budget: &mut ValueBudget,
) -> Result<Variable, String> {
    let attrs = dataset.attrs().map_err(|e| format!("'{name}': the attributes do not read: {e}"))?;
    let skip = |why: String| Ok(Variable::Skipped(format!("'{name}' ({why})")));
    let Some(class) = class_of(&attrs) else {
        return skip("no MATLAB_class attribute: not a MATLAB variable".to_string());
    };
    if !NUMERIC_CLASSES.contains(&class.as_str()) {
        return skip(class);
    }
    let dtype = dataset.dtype().map_err(|e| format!("'{name}': the datatype does not read: {e}"))?;
    let numeric = matches!(
        dtype,
        DType::F32
            | DType::F64
            | DType::I8
            | DType::I16
            | DType::I32
            | DType::I64
            | DType::U8
            | DType::U16
            | DType::U32
            | DType::U64
    );
    if !numeric {
        let what = if matches!(dtype, DType::Compound(_)) { "complex" } else { "not numeric: stored as" };
        return skip(format!("{what} {class}, HDF5 type {dtype}"));
    }
    let shape = dataset.shape().map_err(|e| format!("'{name}': the dataspace does not read: {e}"))?;
    check_size(name, dataset, &shape, file_bytes, budget)?;
    let data = dataset.read_f64().map_err(|e| format!("'{name}': the values do not read: {e}"))?;
    if flag_set(&attrs, "MATLAB_empty") {
        return empty_matrix(name, &class, &data);
    }
    let shape_text = shape.iter().rev().map(|d| d.to_string()).collect::<Vec<_>>().join("x");
    let &[cols, rows] = shape.as_slice() else {
        return skip(format!("{}-d {shape_text}", shape.len()));
    };
    let (rows, cols) = (to_usize(name, rows)?, to_usize(name, cols)?);
    if rows.checked_mul(cols) != Some(data.len()) {
        return Err(format!("'{name}' ({shape_text}): {} values read", data.len()));
    }
    finite_or_refused(name, rows, &data)?;
    Ok(Variable::Matrix(MatMatrix { name: name.to_string(), rows, cols, data }))
}

/// An empty array (`MATLAB_empty` set): its values are its MATLAB dimensions, one of which is 0.
fn empty_matrix(name: &str, class: &str, dims: &[f64]) -> Result<Variable, String> {
    let text = dims.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("x");
    let &[rows, cols] = dims else {
        return Ok(Variable::Skipped(format!("'{name}' (empty {class}, {} dimensions: {text})", dims.len())));
    };
    if !dims.iter().all(|d| d.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(d)) || rows * cols != 0.0 {
        return Err(format!("'{name}': an empty array (MATLAB_empty) whose dimensions are {text}"));
    }
    Ok(Variable::Matrix(MatMatrix { name: name.to_string(), rows: rows as usize, cols: cols as usize, data: vec![] }))
}

/// A dimension as usize.
fn to_usize(name: &str, d: u64) -> Result<usize, String> {
    usize::try_from(d).map_err(|_| format!("'{name}': a dimension of {d} does not fit this machine"))
}

/// Refuses a dataset whose values would take more bytes than the file can hold: the file's length for stored
/// data, deflate's largest ratio times it (at most [`MAX_MAT_VALUE_BYTES`]) for filtered (compressed) data; and
/// one whose values, as f64, pass what is left of the file's budget (taken from it).
fn check_size(
    name: &str,
    dataset: &Dataset,
    shape: &[u64],
    file_bytes: usize,
    budget: &mut ValueBudget,
) -> Result<(), String> {
    let element_bytes = dataset.element_size().map_err(|e| format!("'{name}': the datatype does not read: {e}"))?;
    let count = shape.iter().try_fold(1u64, |n, &d| n.checked_mul(d));
    let stored = count.and_then(|n| n.checked_mul(element_bytes).map(|b| (n, b)));
    let Some((count, stored_bytes)) = stored else {
        return Err(format!("'{name}': the dimensions {shape:?} overflow"));
    };
    let limit = if dataset.filters().is_empty() {
        file_bytes as u64
    } else {
        (file_bytes as u64).saturating_mul(MAX_DEFLATE_RATIO as u64).min(MAX_MAT_VALUE_BYTES as u64)
    };
    if stored_bytes > limit {
        return Err(format!(
            "'{name}': {count} values of {element_bytes} bytes, more than a file of {file_bytes} bytes can hold \
             (at most {limit} bytes)"
        ));
    }
    // The values are converted to f64: 8 bytes each, whatever their stored width.
    budget.take(count).map_err(|r| format!("'{name}': {r}"))
}

/// MATLAB's 512-byte user block of a version 7.3 file: the text header (116 bytes), a zero subsystem offset,
/// the version 0x0200 and the endian indicator `IM`, then zeros.
pub fn user_block() -> Vec<u8> {
    let mut h = b"MATLAB 7.3 MAT-file, Platform: sinscal, written by sinscal HDF5 schema 1.00 .".to_vec();
    h.resize(super::HEADER_TEXT_BYTES, b' ');
    h.extend_from_slice(&[0; 8]);
    h.extend_from_slice(&[0x00, 0x02, b'I', b'M']);
    h.resize(USER_BLOCK_BYTES, 0);
    h
}

/// A version 7.3 MAT-file holding `matrices` (name, rows, cols, column-major values) as double datasets of
/// HDF5 shape [cols, rows], each with `MATLAB_class` "double"; compressed (chunked, deflate, as MATLAB writes
/// by default) when `compress` is set. The same checks as [`super::write_mat_v5`].
pub fn write_mat_v73(matrices: &[NamedMatrix<'_>], compress: bool) -> Result<Vec<u8>, String> {
    let mut file = FileBuilder::new();
    file.with_userblock(USER_BLOCK_BYTES as u64).with_userblock_content(&user_block());
    let mut names: Vec<&str> = Vec::with_capacity(matrices.len());
    for &(name, rows, cols, values) in matrices {
        super::check_matrix(name, rows, cols, values)?;
        if names.contains(&name) {
            return Err(format!("the variable name '{name}' is given twice"));
        }
        names.push(name);
        let ds = file.create_dataset(name);
        ds.with_f64_data(values).with_shape(&[cols as u64, rows as u64]);
        if compress && !values.is_empty() {
            ds.with_chunks(&[cols as u64, rows as u64]).with_deflate(6);
        }
        ds.set_attr("MATLAB_class", AttrValue::AsciiString("double".to_string()));
    }
    file.finish().map_err(|e| format!("the HDF5 file is not written: {e}"))
}

#[cfg(test)]
mod tests {
    use super::super::{read_mat, write_mat_v5};
    use super::*;
    use hdf5_pure::{make_f64_type, CompoundTypeBuilder};

    fn class(name: &str) -> AttrValue {
        AttrValue::AsciiString(name.to_string())
    }

    /// A file as MATLAB's `save -v7.3` lays it out: the user block, then root datasets of HDF5 shape
    /// [cols, rows] with their `MATLAB_class`: a 3x2 double, a 1x5 single (chunked and compressed, as MATLAB
    /// writes by default), a 4x3 int16, a 2x2 logical, an empty 0x3 double, a char row, a complex scalar and a
    /// struct (a group).
    fn matlab_like_file() -> Vec<u8> {
        let mut file = FileBuilder::new();
        file.with_userblock(USER_BLOCK_BYTES as u64).with_userblock_content(&user_block());
        let acc = file.create_dataset("acc");
        acc.with_f64_data(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
            .with_shape(&[2, 3])
            .set_attr("MATLAB_class", class("double"));
        let gyro = file.create_dataset("gyro");
        gyro.with_f32_data(&[0.5, -1.25, 2.0, 1e-3, 7.0]).with_shape(&[5, 1]).with_chunks(&[5, 1]).with_deflate(6);
        gyro.set_attr("MATLAB_class", class("single"));
        let counts: Vec<i16> = (0..12).map(|i| (i * 1000 - 6000) as i16).collect();
        file.create_dataset("counts")
            .with_i16_data(&counts)
            .with_shape(&[3, 4])
            .set_attr("MATLAB_class", class("int16"));
        let flags = file.create_dataset("flags");
        flags.with_u8_data(&[1, 0, 0, 1]).with_shape(&[2, 2]).set_attr("MATLAB_class", class("logical"));
        let nothing = file.create_dataset("nothing");
        nothing.with_u64_data(&[0, 3]).with_shape(&[2]).set_attr("MATLAB_class", class("double"));
        nothing.set_attr("MATLAB_empty", AttrValue::U8(1));
        let units: Vec<u16> = "hello".encode_utf16().collect();
        let label = file.create_dataset("label");
        label.with_u16_data(&units).with_shape(&[5, 1]).set_attr("MATLAB_class", class("char"));
        let complex = CompoundTypeBuilder::new().field("real", make_f64_type()).field("imag", make_f64_type()).build();
        let raw = [1.0f64.to_le_bytes(), 2.0f64.to_le_bytes()].concat();
        let z = file.create_dataset("z");
        z.with_compound_data(complex.unwrap(), raw, 1).with_shape(&[1, 1]).set_attr("MATLAB_class", class("double"));
        let mut s = file.create_group("s");
        s.set_attr("MATLAB_class", class("struct"));
        s.create_dataset("x").with_f64_data(&[9.0]).with_shape(&[1, 1]).set_attr("MATLAB_class", class("double"));
        file.add_group(s.finish());
        file.finish().unwrap()
    }

    fn refusal(bytes: &[u8]) -> String {
        match read_mat(bytes, "test.mat") {
            Ok(m) => panic!("accepted {} matrices, expected a refusal", m.len()),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn the_user_block_is_matlabs_header() {
        let bytes = matlab_like_file();
        assert!(bytes.starts_with(b"MATLAB 7.3 MAT-file, "));
        assert_eq!(&bytes[124..128], &[0x00, 0x02, b'I', b'M']);
        assert_eq!(&bytes[512..520], b"\x89HDF\r\n\x1a\n", "the superblock after the 512-byte user block");
    }

    #[test]
    fn numeric_matrices_read_transposed_to_matlabs_shape() {
        let read = read_mat(&matlab_like_file(), "test.mat").unwrap();
        let shapes: Vec<(&str, usize, usize)> = read.iter().map(|m| (m.name.as_str(), m.rows, m.cols)).collect();
        // In the order the root group lists them (here the order of writing; by name in MATLAB's files).
        assert_eq!(shapes, [("acc", 3, 2), ("gyro", 1, 5), ("counts", 4, 3), ("flags", 2, 2), ("nothing", 0, 3)]);
        let acc = &read[0];
        assert_eq!(acc.data, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        // Column-major: the first column is 1, 2, 3; row 1 (0-based 0) is 1, 4.
        assert_eq!((acc.get(0, 1), acc.get(2, 0), acc.get(2, 1)), (Some(4.0), Some(3.0), Some(6.0)));
        assert_eq!(acc.column(1), Some(&[4.0, 5.0, 6.0][..]));
        let counts = &read[2];
        let expected: Vec<f64> = (0..12).map(|i| (i * 1000 - 6000) as f64).collect();
        assert_eq!(counts.data, expected);
        assert_eq!((counts.get(3, 0), counts.get(0, 1)), (Some(-3000.0), Some(-2000.0)));
        assert_eq!(read[3].data, [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(read[1].data, [0.5, -1.25, 2.0, 1e-3f32 as f64, 7.0]);
        assert!(read[4].data.is_empty());
    }

    #[test]
    fn char_complex_and_structs_are_skipped_and_named_when_nothing_is_left() {
        let mut file = FileBuilder::new();
        file.with_userblock(USER_BLOCK_BYTES as u64).with_userblock_content(&user_block());
        let units: Vec<u16> = "hi".encode_utf16().collect();
        file.create_dataset("label").with_u16_data(&units).with_shape(&[2, 1]).set_attr("MATLAB_class", class("char"));
        file.create_dataset("plain").with_f64_data(&[1.0]).with_shape(&[1, 1]);
        let cube = file.create_dataset("cube");
        cube.with_f64_data(&[1.0; 8]).with_shape(&[2, 2, 2]).set_attr("MATLAB_class", class("double"));
        let mut s = file.create_group("s");
        s.set_attr("MATLAB_class", class("struct"));
        file.add_group(s.finish());
        let e = refusal(&file.finish().unwrap());
        for what in ["'label' (char)", "'plain' (no MATLAB_class", "'cube' (3-d 2x2x2)", "'s' (struct)"] {
            assert!(e.contains(what), "'{e}' does not name {what}");
        }
        assert!(e.contains("no numeric 2-D real matrix"), "{e}");
        // And in the full file, the complex scalar is named among the skipped only if nothing else is read.
        let read = read_mat(&matlab_like_file(), "test.mat").unwrap();
        assert!(read.iter().all(|m| !["label", "z", "s"].contains(&m.name.as_str())));
    }

    #[test]
    fn writer_round_trips_plain_and_compressed() {
        let imu: Vec<f64> = (0..21).map(|i| (i as f64 * 0.37).sin() * 10f64.powi(i % 7 - 3)).collect();
        let odd = [-0.0, 5e-324, f64::MAX, f64::MIN, f64::MIN_POSITIVE, 1.0 / 3.0];
        let written: [NamedMatrix<'_>; 3] = [("imu_3x7", 3, 7, &imu), ("odd", 2, 3, &odd), ("row", 1, 21, &imu)];
        for compress in [false, true] {
            let bytes = write_mat_v73(&written, compress).unwrap();
            let read = read_mat(&bytes, "test.mat").unwrap();
            assert_eq!(read.len(), 3);
            for (m, &(name, rows, cols, values)) in read.iter().zip(&written) {
                assert_eq!((m.name.as_str(), m.rows, m.cols), (name, rows, cols));
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&m.data), bits(values), "{name}");
            }
            assert_eq!(read[0].get(2, 6), Some(imu[20]));
        }
        assert!(write_mat_v73(&[("a", 1, 2, &[1.0, f64::NAN])], false).unwrap_err().contains("is NaN"));
        assert!(write_mat_v73(&[("a", 1, 1, &[1.0]), ("a", 1, 1, &[2.0])], false).unwrap_err().contains("twice"));
    }

    #[test]
    fn non_finite_values_are_refused_by_place() {
        let mut file = FileBuilder::new();
        file.with_userblock(USER_BLOCK_BYTES as u64).with_userblock_content(&user_block());
        let acc = file.create_dataset("acc");
        acc.with_f64_data(&[1.0, 2.0, 3.0, f64::INFINITY])
            .with_shape(&[2, 2])
            .set_attr("MATLAB_class", class("double"));
        let e = refusal(&file.finish().unwrap());
        assert!(e.contains("'acc': the value at row 2, column 2 is inf: sinscal reads finite values only"), "{e}");
    }

    #[test]
    fn a_v73_header_with_garbage_hdf5_is_refused_with_a_reason() {
        let good = write_mat_v73(&[("a", 2, 2, &[1.0, 2.0, 3.0, 4.0])], false).unwrap();
        let mut garbage = good[..520].to_vec();
        garbage.extend((0..2000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
        let e = refusal(&garbage);
        assert!(e.starts_with("test.mat: MATLAB 7.3: the HDF5 data do not read"), "{e}");
        let e = refusal(&good[..300]);
        assert!(e.contains("MATLAB 7.3 header without the HDF5 signature at byte 512"), "{e}");
        // HDF5 without MATLAB's header, at byte 512 or 0: not a MAT-file.
        let mut no_header = good.clone();
        no_header[..512].fill(0);
        assert!(refusal(&no_header).contains("an HDF5 file without MATLAB's header"));
        assert!(refusal(&good[512..]).contains("an HDF5 file without MATLAB's header"));
        // A level-5 file is still read by the level-5 path.
        assert_eq!(read_mat(&write_mat_v5(&[("a", 1, 1, &[1.0])]).unwrap(), "t").unwrap().len(), 1);
    }

    #[test]
    fn every_cut_and_many_corruptions_are_refused_without_panic() {
        let bytes = write_mat_v73(&[("a", 1, 1, &[2.5]), ("imu", 3, 7, &[0.25; 21])], true).unwrap();
        for len in 0..bytes.len() {
            if let Ok(m) = read_mat(&bytes[..len], "test.mat") {
                assert!(m.iter().all(|m| m.data.len() == m.rows * m.cols), "cut at {len}");
            }
        }
        for at in 512..bytes.len() {
            for flip in [0x01u8, 0x80, 0xff] {
                let mut bad = bytes.clone();
                bad[at] ^= flip;
                if let Ok(m) = read_mat(&bad, "test.mat") {
                    assert!(m.iter().all(|m| m.data.len() == m.rows * m.cols && m.data.iter().all(|v| v.is_finite())));
                }
            }
        }
    }

    /// Bob Jenkins' lookup3 `hashlittle` with seed 0: HDF5's checksum of its metadata blocks.
    fn lookup3(data: &[u8]) -> u32 {
        let mut abc = [0xdead_beefu32.wrapping_add(data.len() as u32); 3];
        let word = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        let add = |abc: &mut [u32; 3], block: &[u8]| {
            for (x, w) in abc.iter_mut().zip(block.chunks(4)) {
                *x = x.wrapping_add(word(w));
            }
        };
        let step = |abc: &mut [u32; 3], i: usize, j: usize, k: usize, r: u32| {
            abc[i] = abc[i].wrapping_sub(abc[k]);
            abc[i] ^= abc[k].rotate_left(r);
            abc[k] = abc[k].wrapping_add(abc[j]);
        };
        let mut rest = data;
        while rest.len() > 12 {
            add(&mut abc, &rest[..12]);
            for (i, r) in [4, 6, 8, 16, 19, 4].into_iter().enumerate() {
                step(&mut abc, i % 3, (i + 1) % 3, (i + 2) % 3, r);
            }
            rest = &rest[12..];
        }
        if rest.is_empty() {
            return abc[2];
        }
        let mut last = [0u8; 12];
        last[..rest.len()].copy_from_slice(rest);
        add(&mut abc, &last);
        for (i, r) in [14, 11, 25, 16, 4, 14, 24].into_iter().enumerate() {
            let (x, y) = ([2, 0, 1][i % 3], [1, 2, 0][i % 3]);
            abc[x] ^= abc[y];
            abc[x] = abc[x].wrapping_sub(abc[y].rotate_left(r));
        }
        abc[2]
    }

    #[test]
    fn a_dataset_larger_than_the_file_is_refused_before_it_is_read() {
        let mut bytes = write_mat_v73(&[("huge", 5, 7, &[1.0; 35])], false).unwrap();
        assert_eq!(read_mat(&bytes, "test.mat").unwrap()[0].rows, 5);
        // The dataspace's dimensions [7, 5] become [2^20, 2^20], and the object header's checksum follows.
        let dims = [7u64.to_le_bytes(), 5u64.to_le_bytes()].concat();
        let at: Vec<usize> = (512..bytes.len() - 16).filter(|&i| bytes[i..i + 16] == dims[..]).collect();
        assert_eq!(at.len(), 1, "the dataspace's dimensions are found once");
        let header = (512..at[0]).rev().find(|&i| &bytes[i..i + 4] == b"OHDR").expect("a version 2 object header");
        let sum_at = (at[0] + 16..bytes.len() - 4)
            .find(|&q| lookup3(&bytes[header..q]).to_le_bytes() == bytes[q..q + 4])
            .expect("the object header's checksum");
        for d in [at[0], at[0] + 8] {
            bytes[d..d + 8].copy_from_slice(&(1u64 << 20).to_le_bytes());
        }
        let sum = lookup3(&bytes[header..sum_at]).to_le_bytes();
        bytes[sum_at..sum_at + 4].copy_from_slice(&sum);
        let e = refusal(&bytes);
        assert!(e.contains("'huge': 1099511627776 values of 8 bytes, more than a file of"), "{e}");
    }
}
