//! Reading meshes: STL (binary or ASCII, by `stl_io`) and Wavefront OBJ
//! (by `tobj`, triangulated), from bytes or from one file, the crate's
//! only I/O.
use crate::{Shape3dError, TriangleMesh, Vec3};
use std::path::Path;

/// The mesh file formats this crate reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshFormat {
    Stl,
    Obj,
}

impl MeshFormat {
    /// The format named by a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "stl" => Some(Self::Stl),
            "obj" => Some(Self::Obj),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Stl => "STL",
            Self::Obj => "OBJ",
        }
    }
}

impl TriangleMesh {
    /// A mesh from the bytes of an STL or OBJ file (coordinates in mm).
    /// An OBJ file's materials are not read; its objects are merged.
    pub fn from_bytes(bytes: &[u8], format: MeshFormat) -> Result<Self, Shape3dError> {
        let bad = |reason: String| Shape3dError::Mesh {
            format: format.name(),
            reason,
        };
        let (vertices, triangles) = match format {
            MeshFormat::Stl => {
                let mesh = stl_io::read_stl(&mut std::io::Cursor::new(bytes))
                    .map_err(|e| bad(e.to_string()))?;
                let vertices = mesh
                    .vertices
                    .iter()
                    .map(|v| Vec3::new(v.0[0].into(), v.0[1].into(), v.0[2].into()))
                    .collect();
                let triangles = mesh.faces.iter().map(|f| f.vertices).collect();
                (vertices, triangles)
            }
            MeshFormat::Obj => read_obj(bytes).map_err(bad)?,
        };
        TriangleMesh::new(vertices, triangles).map_err(|e| match e {
            Shape3dError::Mesh { reason, .. } => bad(reason),
            other => other,
        })
    }

    /// Read a mesh file, its format from the extension (.stl or .obj).
    pub fn read(path: &Path) -> Result<Self, Shape3dError> {
        let format = MeshFormat::from_path(path).ok_or_else(|| Shape3dError::UnknownFormat {
            path: path.to_path_buf(),
        })?;
        let bytes = std::fs::read(path).map_err(|source| Shape3dError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes, format)
    }
}

type Triangles = (Vec<Vec3>, Vec<[usize; 3]>);

fn read_obj(bytes: &[u8]) -> Result<Triangles, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| e.to_string())?;
    let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
    for model in models {
        let base = vertices.len();
        let p = &model.mesh.positions;
        vertices.extend(
            p.chunks_exact(3)
                .map(|c| Vec3::new(c[0].into(), c[1].into(), c[2].into())),
        );
        triangles.extend(model.mesh.indices.chunks_exact(3).map(|t| {
            [
                base + t[0] as usize,
                base + t[1] as usize,
                base + t[2] as usize,
            ]
        }));
    }
    Ok((vertices, triangles))
}
