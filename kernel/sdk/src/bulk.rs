//! Arrays a host hands to `create` by pointer instead of as parameter text
//! (the Python module's meshes from NumPy arrays): [`Env::arrays`].
//!
//! Why by pointer: a million-vertex mesh as TOML text would be formatted,
//! parsed and rounded twice; as a [`BulkArray`] it is one copy, and f64
//! positions stay f64 until [`Env::place`](crate::Env::place) moves them to
//! the renderer's origin. The views here read the host's bytes without
//! assuming alignment, so a host may pass any buffer it owns.
//!
//! [`Env::arrays`]: crate::Env::arrays

use crate::PluginError;
use rtk_abi::{bulk_dtype, BulkArray};

/// The arrays of one `create` call, valid during it (copy what you keep).
#[derive(Clone, Copy, Debug, Default)]
pub struct Arrays<'a> {
    list: &'a [BulkArray],
}

/// One array: its parameter name, element type and shape, and its bytes.
#[derive(Clone, Copy, Debug)]
pub struct ArrayView<'a> {
    /// The parameter it stands for (`vertices`).
    pub name: &'a str,
    /// A [`bulk_dtype`].
    pub dtype: u32,
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    bytes: &'a [u8],
}

/// Bytes per element of a [`bulk_dtype`], or `None` for an unknown code.
fn element_size(dtype: u32) -> Option<usize> {
    match dtype {
        bulk_dtype::F32 | bulk_dtype::U32 | bulk_dtype::I32 => Some(4),
        bulk_dtype::F64 | bulk_dtype::I64 => Some(8),
        bulk_dtype::U8 => Some(1),
        _ => None,
    }
}

impl<'a> Arrays<'a> {
    /// No arrays (a scene file's definitions).
    pub const NONE: Arrays<'static> = Arrays { list: &[] };

    /// # Safety
    /// Every record's name and data must be valid for `'a`, the data
    /// holding `rows * cols` elements of its dtype.
    pub(crate) unsafe fn from_raw(list: &'a [BulkArray]) -> Self {
        Arrays { list }
    }

    /// Whether the host passed none.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The names passed, in the host's order.
    pub fn names(&self) -> impl Iterator<Item = &'a str> + 'a {
        let list = self.list;
        (0..list.len()).filter_map(move |i| Self { list }.view(i).map(|v| v.name))
    }

    /// The array named `name`, if the host passed it.
    pub fn get(&self, name: &str) -> Option<ArrayView<'a>> {
        (0..self.list.len())
            .filter_map(|i| self.view(i))
            .find(|v| v.name == name)
    }

    fn view(&self, i: usize) -> Option<ArrayView<'a>> {
        let r = &self.list[i];
        let size = element_size(r.dtype)?;
        let (rows, cols) = (usize::try_from(r.rows).ok()?, usize::try_from(r.cols).ok()?);
        let len = rows.checked_mul(cols)?.checked_mul(size)?;
        // SAFETY: `from_raw`'s contract: the name and `rows * cols`
        // elements of data are valid for 'a.
        let (name, bytes) = unsafe {
            (
                std::slice::from_raw_parts(r.name.ptr, r.name.len),
                if len == 0 {
                    &[][..]
                } else {
                    std::slice::from_raw_parts(r.data, len)
                },
            )
        };
        Some(ArrayView {
            name: std::str::from_utf8(name).ok()?,
            dtype: r.dtype,
            rows,
            cols,
            bytes,
        })
    }
}

impl ArrayView<'_> {
    fn shape_error(&self, cols: usize) -> PluginError {
        PluginError::key(
            self.name,
            format!(
                "expected an array of N x {cols}, got {} x {}",
                self.rows, self.cols
            ),
        )
    }

    /// Rows of `N` floats (f32 or f64), widened to f64 exactly.
    pub fn rows_f64<const N: usize>(&self) -> Result<Vec<[f64; N]>, PluginError> {
        if self.cols != N {
            return Err(self.shape_error(N));
        }
        let flat: Vec<f64> = match self.dtype {
            bulk_dtype::F32 => self
                .bytes
                .chunks_exact(4)
                .map(|b| f32::from_ne_bytes(b.try_into().unwrap()) as f64)
                .collect(),
            bulk_dtype::F64 => self
                .bytes
                .chunks_exact(8)
                .map(|b| f64::from_ne_bytes(b.try_into().unwrap()))
                .collect(),
            _ => {
                return Err(PluginError::key(
                    self.name,
                    "expected float32 or float64 elements",
                ))
            }
        };
        Ok(flat
            .chunks_exact(N)
            .map(|c| std::array::from_fn(|i| c[i]))
            .collect())
    }

    /// Rows of `N` non-negative integers (any integer dtype) below `bound`.
    pub fn rows_index<const N: usize>(&self, bound: u32) -> Result<Vec<[u32; N]>, PluginError> {
        if self.cols != N {
            return Err(self.shape_error(N));
        }
        let flat: Vec<i64> = match self.dtype {
            bulk_dtype::I32 => self
                .bytes
                .chunks_exact(4)
                .map(|b| i32::from_ne_bytes(b.try_into().unwrap()) as i64)
                .collect(),
            bulk_dtype::U32 => self
                .bytes
                .chunks_exact(4)
                .map(|b| u32::from_ne_bytes(b.try_into().unwrap()) as i64)
                .collect(),
            bulk_dtype::I64 => self
                .bytes
                .chunks_exact(8)
                .map(|b| i64::from_ne_bytes(b.try_into().unwrap()))
                .collect(),
            _ => return Err(PluginError::key(self.name, "expected integer elements")),
        };
        if let Some((i, v)) = flat
            .iter()
            .enumerate()
            .find(|(_, &v)| v < 0 || v >= bound as i64)
        {
            return Err(PluginError::key(
                self.name,
                format!("row {} holds {v}: indices must lie in [0, {bound})", i / N),
            ));
        }
        Ok(flat
            .chunks_exact(N)
            .map(|c| std::array::from_fn(|i| c[i] as u32))
            .collect())
    }
}
