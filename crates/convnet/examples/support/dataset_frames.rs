//! A tactrace dataset folder's frames and targets, as `tactrace twin
//! --frames-size` or `import --frames-size` write them: `frames.npy`
//! (uint8, N x H x W) and `targets.npy` (float32, N x T, the targets in
//! `meta.json`'s order; for an edge set r mm, then theta deg). Read here
//! with a small `.npy` reader (little-endian, C order, the two types
//! above only), since the example cannot depend on the store crate.
use std::error::Error;
use std::path::Path;

/// A dataset's frames (`count` of `side x side` px) and their targets
/// (`dim` a frame).
pub struct DatasetFrames {
    pub pixels: Vec<u8>,
    pub targets: Vec<f64>,
    pub count: usize,
    pub side: usize,
    pub dim: usize,
}

/// The frames and targets of the dataset folder `dir`.
pub fn read(dir: &Path) -> Result<DatasetFrames, Box<dyn Error>> {
    let (fshape, pixels) = read_npy(&dir.join("frames.npy"), "|u1")?;
    let (tshape, raw) = read_npy(&dir.join("targets.npy"), "<f4")?;
    let [count, h, w] = fshape[..] else {
        return Err(format!("{}: frames.npy is not N x H x W", dir.display()).into());
    };
    let [rows, dim] = tshape[..] else {
        return Err(format!("{}: targets.npy is not N x T", dir.display()).into());
    };
    if h != w || rows != count {
        return Err(format!(
            "{}: {count} frames of {h} x {w} px against {rows} target rows",
            dir.display()
        )
        .into());
    }
    let targets = raw
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
        .collect();
    Ok(DatasetFrames {
        pixels,
        targets,
        count,
        side: w,
        dim,
    })
}

/// The shape and data bytes of the `.npy` file `path`, whose `descr`
/// must be `descr` (C order).
fn read_npy(path: &Path, descr: &str) -> Result<(Vec<usize>, Vec<u8>), Box<dyn Error>> {
    let bytes = std::fs::read(path)?;
    let bad = |why: &str| format!("{}: {why}", path.display());
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(bad("not a .npy file").into());
    }
    let (len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        _ if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        _ => return Err(bad("a truncated header").into()),
    };
    let header = std::str::from_utf8(bytes.get(start..start + len).ok_or(bad("short"))?)?;
    if !header.contains(&format!("'descr': '{descr}'")) || header.contains("'fortran_order': True")
    {
        return Err(bad(&format!("not a C-order {descr} array: {header}")).into());
    }
    let inside = header
        .split_once("'shape': (")
        .and_then(|(_, rest)| rest.split_once(')'))
        .ok_or(bad("no shape"))?
        .0;
    let shape = inside
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>())
        .collect::<Result<Vec<_>, _>>()?;
    let data = bytes[start + len..].to_vec();
    let item = if descr == "|u1" { 1 } else { 4 };
    if data.len() != shape.iter().product::<usize>() * item {
        return Err(bad("its data does not match its shape").into());
    }
    Ok((shape, data))
}
