//! What every model file shares, written once for the image models (this
//! crate) and the pin models (`tactrace-learn`): the JSON header's format
//! name and version, and the safetensors weights (named tensors of
//! little-endian f32 or f64, each read back checked against the dtype and
//! shape the model expects). Pure: bytes in, bytes out; each model's own
//! error type wraps a [`ModelFileError`] as a corrupt file.
use safetensors::tensor::TensorView;
use safetensors::{Dtype, SafeTensorError, SafeTensors};

/// Why a model file's shared parts cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    /// The JSON is not JSON.
    #[error("model json")]
    Json {
        #[source]
        source: serde_json::Error,
    },
    /// The JSON names another format.
    #[error("not a {format} file")]
    Format { format: &'static str },
    /// The JSON has no version number.
    #[error("model json has no version")]
    NoVersion,
    /// The safetensors bytes are not a safetensors file.
    #[error("weights")]
    Weights {
        #[source]
        source: SafeTensorError,
    },
    /// A tensor is missing.
    #[error("tensor {name}")]
    Missing {
        name: String,
        #[source]
        source: SafeTensorError,
    },
    /// A tensor has another dtype or shape than the model's.
    #[error(
        "tensor {name}: expected {expected} {}, found {found} {}",
        dims(.expected_shape),
        dims(.found_shape)
    )]
    Shape {
        name: String,
        expected: Dtype,
        expected_shape: Vec<usize>,
        found: Dtype,
        found_shape: Vec<usize>,
    },
    /// The tensors could not be laid out (a shape that does not match its
    /// bytes: a bug of the caller).
    #[error("the weights cannot be laid out as safetensors")]
    Write {
        #[source]
        source: SafeTensorError,
    },
}

impl ModelFileError {
    /// The message and its cause's, one line, for a model's
    /// corrupt-file error (which holds a reason, not a source).
    pub fn reason(&self) -> String {
        match std::error::Error::source(self) {
            Some(cause) => format!("{self}: {cause}"),
            None => self.to_string(),
        }
    }
}

/// A shape as `a x b x c`.
fn dims(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(usize::to_string).collect();
    parts.join(" x ")
}

/// The model JSON `json` parsed, with its version, when it names the
/// format `format` and has a version number (which the caller checks).
pub fn read_header(
    json: &str,
    format: &'static str,
) -> Result<(serde_json::Value, u64), ModelFileError> {
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|source| ModelFileError::Json { source })?;
    if value.get("format").and_then(|f| f.as_str()) != Some(format) {
        return Err(ModelFileError::Format { format });
    }
    let version = value
        .get("version")
        .and_then(|v| v.as_u64())
        .ok_or(ModelFileError::NoVersion)?;
    Ok((value, version))
}

/// One named tensor to write: its dtype, shape and little-endian bytes.
pub struct Tensor {
    name: String,
    dtype: Dtype,
    shape: Vec<usize>,
    bytes: Vec<u8>,
}

impl Tensor {
    /// An f32 tensor `name` of `shape` holding `values` (row-major).
    pub fn f32(name: impl Into<String>, shape: Vec<usize>, values: &[f32]) -> Self {
        let bytes = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        Self::new(name.into(), Dtype::F32, shape, bytes)
    }

    /// An f64 tensor `name` of `shape` holding `values` (row-major).
    pub fn f64(name: impl Into<String>, shape: Vec<usize>, values: &[f64]) -> Self {
        let bytes = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        Self::new(name.into(), Dtype::F64, shape, bytes)
    }

    fn new(name: String, dtype: Dtype, shape: Vec<usize>, bytes: Vec<u8>) -> Self {
        Self {
            name,
            dtype,
            shape,
            bytes,
        }
    }
}

/// The safetensors bytes of `tensors` (no metadata).
pub fn write_tensors(tensors: &[Tensor]) -> Result<Vec<u8>, ModelFileError> {
    let write = |source| ModelFileError::Write { source };
    let views = tensors
        .iter()
        .map(|t| TensorView::new(t.dtype, t.shape.clone(), &t.bytes).map(|v| (t.name.clone(), v)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(write)?;
    safetensors::serialize(views, None).map_err(write)
}

/// The safetensors file `bytes`, parsed.
pub fn read_tensors(bytes: &[u8]) -> Result<SafeTensors<'_>, ModelFileError> {
    SafeTensors::deserialize(bytes).map_err(|source| ModelFileError::Weights { source })
}

/// The bytes of tensor `name`, which must be of `dtype` and `shape`.
fn tensor_bytes<'a>(
    tensors: &'a SafeTensors,
    name: &str,
    dtype: Dtype,
    shape: &[usize],
) -> Result<&'a [u8], ModelFileError> {
    let view = tensors
        .tensor(name)
        .map_err(|source| ModelFileError::Missing {
            name: name.to_string(),
            source,
        })?;
    if view.dtype() != dtype || view.shape() != shape {
        return Err(ModelFileError::Shape {
            name: name.to_string(),
            expected: dtype,
            expected_shape: shape.to_vec(),
            found: view.dtype(),
            found_shape: view.shape().to_vec(),
        });
    }
    Ok(view.data())
}

/// The f32 values of tensor `name` of `shape`.
pub fn read_f32(
    tensors: &SafeTensors,
    name: &str,
    shape: &[usize],
) -> Result<Vec<f32>, ModelFileError> {
    Ok(tensor_bytes(tensors, name, Dtype::F32, shape)?
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

/// The f64 values of tensor `name` of `shape`.
pub fn read_f64(
    tensors: &SafeTensors,
    name: &str,
    shape: &[usize],
) -> Result<Vec<f64>, ModelFileError> {
    Ok(tensor_bytes(tensors, name, Dtype::F64, shape)?
        .chunks_exact(8)
        .map(f64_of)
        .collect())
}

/// One little-endian f64 of 8 bytes.
fn f64_of(c: &[u8]) -> f64 {
    f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])
}
