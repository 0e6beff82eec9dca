//! `.npy` arrays read with the size their header declares checked against
//! the file's before anything is allocated: a header claiming
//! (100000000, 254) in a 1 KB file is refused, not allocated.
use crate::error::{read_err, Result, StoreError};
use crate::input_file::open_regular;
use ndarray::{Array2, Array3};
use ndarray_npy::npy::header::Header;
use ndarray_npy::ReadNpyExt;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// The `.npy` magic string.
const MAGIC: &[u8] = b"\x93NUMPY";

/// The longest header accepted, bytes (numpy writes well under 1 KB).
const MAX_HEADER: usize = 1 << 20;

/// Read a 2-D float32 `.npy` file whose data is exactly what its header
/// declares.
pub fn read_f32_matrix(path: &Path) -> Result<Array2<f32>> {
    let file = open_checked(path)?;
    Array2::<f32>::read_npy(BufReader::new(file)).map_err(|e| StoreError::Format {
        path: path.to_path_buf(),
        reason: format!("not a 2-D float32 .npy file: {e}"),
    })
}

/// Read a 3-D uint8 `.npy` file (a stack of grey frames, `N x H x W`)
/// whose data is exactly what its header declares.
pub fn read_u8_stack(path: &Path) -> Result<Array3<u8>> {
    let file = open_checked(path)?;
    Array3::<u8>::read_npy(BufReader::new(file)).map_err(|e| StoreError::Format {
        path: path.to_path_buf(),
        reason: format!("not a 3-D uint8 .npy file: {e}"),
    })
}

/// The `.npy` file at `path`, opened and rewound, once its header's shape
/// and value size are found to match the bytes it holds.
fn open_checked(path: &Path) -> Result<std::fs::File> {
    let (mut file, len) = open_regular(path)?;
    let fmt = |reason: String| StoreError::Format {
        path: path.to_path_buf(),
        reason,
    };
    let (header, header_bytes) = read_header(&mut file, len).map_err(fmt)?;
    let item = item_size(&header);
    let values = header
        .shape
        .iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d));
    let data = values.and_then(|n| n.checked_mul(item));
    let held = len - header_bytes as u64;
    if data.map(|d| d as u64) != Some(held) {
        let shape: Vec<String> = header.shape.iter().map(|d| d.to_string()).collect();
        return Err(fmt(format!(
            "its header declares a {} array of {item}-byte values ({}), but the file holds \
             {held} bytes of data: a damaged or truncated .npy file",
            shape.join(" x "),
            data.map_or("more bytes than can be counted".into(), |d| format!(
                "{d} bytes"
            )),
        )));
    }
    file.seek(SeekFrom::Start(0)).map_err(read_err(path))?;
    Ok(file)
}

/// The header of the `.npy` file `file` of `len` bytes, and how many bytes
/// it takes (magic, version, length and the header itself).
fn read_header(file: &mut std::fs::File, len: u64) -> std::result::Result<(Header, usize), String> {
    let mut prefix = Vec::with_capacity(12);
    file.by_ref()
        .take(12)
        .read_to_end(&mut prefix)
        .map_err(|e| e.to_string())?;
    let got = prefix.len();
    let not_npy = || "not a .npy file (no NUMPY header)".to_string();
    if got < 10 || &prefix[..6] != MAGIC {
        return Err(not_npy());
    }
    let (start, header_len) = match prefix[6] {
        1 => (10, u16::from_le_bytes([prefix[8], prefix[9]]) as usize),
        2 | 3 if got == 12 => (
            12,
            u32::from_le_bytes([prefix[8], prefix[9], prefix[10], prefix[11]]) as usize,
        ),
        _ => return Err(not_npy()),
    };
    let total = start + header_len;
    if header_len > MAX_HEADER || total as u64 > len {
        return Err(format!(
            "its header claims {header_len} bytes, more than the file (or a .npy header) holds"
        ));
    }
    let mut bytes = prefix[..start].to_vec();
    bytes.resize(total, 0);
    file.seek(SeekFrom::Start(start as u64))
        .and_then(|_| file.read_exact(&mut bytes[start..]))
        .map_err(|e| e.to_string())?;
    let header =
        Header::from_reader(&mut &bytes[..]).map_err(|e| format!("not a .npy file: {e}"))?;
    Ok((header, total))
}

/// Bytes a value of the header's type takes (`<f4` -> 4); 4 when the
/// type is not a plain one (the reader then refuses it by type).
fn item_size(header: &Header) -> usize {
    let descr = header.type_descriptor.to_string();
    let digits: String = descr
        .trim_matches(|c| c == '\'' || c == '"')
        .chars()
        .skip_while(|c| !c.is_ascii_digit())
        .take_while(|c| c.is_ascii_digit())
        .collect();
    digits.parse().ok().filter(|&n| n > 0).unwrap_or(4)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A v1 `.npy` file: header dict for `shape` (as written in Python),
    /// then `data` bytes.
    fn npy(shape: &str, data: &[u8]) -> Vec<u8> {
        let mut dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {shape}, }}");
        while (10 + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut out = MAGIC.to_vec();
        out.extend([1, 0]);
        out.extend((dict.len() as u16).to_le_bytes());
        out.extend(dict.as_bytes());
        out.extend(data);
        out
    }

    #[test]
    fn a_header_claiming_more_than_the_file_holds_is_refused() {
        let root = tempfile::tempdir().unwrap();
        let p = root.path().join("inputs.npy");
        std::fs::write(&p, npy("(100000000, 254)", &[0u8; 1000])).unwrap();
        let msg = read_f32_matrix(&p).unwrap_err().to_string();
        assert!(
            msg.contains("declares a 100000000 x 254 array")
                && msg.contains("101600000000 bytes")
                && msg.contains("holds 1000 bytes"),
            "{msg}"
        );
        // A shape whose size overflows.
        let huge = format!("({}, {})", usize::MAX, usize::MAX);
        std::fs::write(&p, npy(&huge, &[])).unwrap();
        let msg = read_f32_matrix(&p).unwrap_err().to_string();
        assert!(msg.contains("more bytes than can be counted"), "{msg}");
        // A header length past the end of the file.
        let mut bytes = npy("(1, 1)", &[0; 4]);
        bytes[8] = 0xff;
        bytes[9] = 0xff;
        std::fs::write(&p, &bytes).unwrap();
        let msg = read_f32_matrix(&p).unwrap_err().to_string();
        assert!(msg.contains("header claims 65535 bytes"), "{msg}");
    }

    #[test]
    fn a_well_formed_file_reads_back() {
        let root = tempfile::tempdir().unwrap();
        let p = root.path().join("a.npy");
        let a = Array2::from_shape_vec((2, 3), vec![1f32, 2., 3., 4., 5., 6.]).unwrap();
        ndarray_npy::write_npy(&p, &a).unwrap();
        assert_eq!(read_f32_matrix(&p).unwrap(), a);
        let data: Vec<u8> = [1f32, 2.].iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&p, npy("(1, 2)", &data)).unwrap();
        assert_eq!(read_f32_matrix(&p).unwrap().dim(), (1, 2));
        std::fs::write(&p, b"hello").unwrap();
        assert!(read_f32_matrix(&p)
            .unwrap_err()
            .to_string()
            .contains("not a .npy"));
    }
}
