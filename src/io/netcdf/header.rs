//! The header of a classic NetCDF file (CDF-1, and CDF-2 with 64-bit offsets): dimensions,
//! global attributes and variables with their attributes, type and where their data begins.
//! Every count in the header is checked against the bytes left before anything is allocated
//! for it, so a damaged header is a one-line error, never a huge allocation or a panic. CDF-5
//! (64-bit data, NetCDF-4 is HDF5) is refused with a message that says so. Errors are
//! [`NetcdfError`]s.

use super::error::NetcdfError;

/// A NetCDF external type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NcType {
    Byte,
    Char,
    Short,
    Int,
    Float,
    Double,
}

impl NcType {
    fn from_code(code: u32) -> Result<NcType, NetcdfError> {
        Ok(match code {
            1 => NcType::Byte,
            2 => NcType::Char,
            3 => NcType::Short,
            4 => NcType::Int,
            5 => NcType::Float,
            6 => NcType::Double,
            _ => return Err(NetcdfError::UnknownType(code)),
        })
    }

    /// Bytes per value.
    pub(crate) fn size(self) -> u64 {
        match self {
            NcType::Byte | NcType::Char => 1,
            NcType::Short => 2,
            NcType::Int | NcType::Float => 4,
            NcType::Double => 8,
        }
    }
}

/// An attribute's values.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    Text(String),
    /// Numbers of any numeric type, with the type they were stored as.
    Numbers(NcType, Vec<f64>),
}

/// A named attribute.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Attribute {
    pub name: String,
    pub value: Value,
}

/// A dimension: its name and length (0 for the record dimension).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Dimension {
    pub name: String,
    pub len: u64,
}

/// A variable: its dimensions (indices into [`Header::dimensions`]), attributes, type and the
/// byte offset of its data (of its first record, for a record variable).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Variable {
    pub name: String,
    pub dimensions: Vec<usize>,
    pub attributes: Vec<Attribute>,
    pub kind: NcType,
    pub begin: u64,
}

impl Variable {
    /// The attribute called `name`.
    pub(crate) fn attribute(&self, name: &str) -> Option<&Value> {
        find(&self.attributes, name)
    }
}

/// A parsed header.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Header {
    /// Records the header announces; `None` for a file being written (streaming).
    pub records: Option<u64>,
    pub dimensions: Vec<Dimension>,
    pub attributes: Vec<Attribute>,
    pub variables: Vec<Variable>,
}

impl Header {
    /// The global attribute called `name`.
    pub(crate) fn attribute(&self, name: &str) -> Option<&Value> {
        find(&self.attributes, name)
    }

    /// The index of the dimension called `name`.
    pub(crate) fn dimension(&self, name: &str) -> Option<usize> {
        self.dimensions.iter().position(|d| d.name == name)
    }

    /// The variable called `name`.
    pub(crate) fn variable(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }
}

fn find<'a>(attributes: &'a [Attribute], name: &str) -> Option<&'a Value> {
    attributes.iter().find(|a| a.name == name).map(|a| &a.value)
}

/// Why parsing stopped: the bytes ran out (read more of the file and retry) or the header is
/// damaged.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum HeaderError {
    NeedMore,
    Damaged(NetcdfError),
}

impl From<NetcdfError> for HeaderError {
    fn from(reason: NetcdfError) -> Self {
        HeaderError::Damaged(reason)
    }
}

/// A cursor over the header bytes read so far; `file_len` bounds every count.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
    file_len: u64,
}

impl Cursor<'_> {
    fn take(&mut self, n: u64) -> Result<&[u8], HeaderError> {
        let left = self.file_len.saturating_sub(self.at as u64);
        if n > left {
            return Err(HeaderError::Damaged(NetcdfError::Truncated {
                bytes: n,
                at: self.at,
                file_len: self.file_len,
            }));
        }
        let end = self.at + n as usize;
        if end > self.bytes.len() {
            return Err(HeaderError::NeedMore);
        }
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn u32(&mut self) -> Result<u32, HeaderError> {
        let b = self.take(4)?;
        Ok(u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A count of `what`: a non-negative 32-bit integer, at most what the bytes left can hold
    /// at `each` bytes per element.
    fn count(&mut self, what: &'static str, each: u64) -> Result<u64, HeaderError> {
        let n = self.u32()?;
        if n > i32::MAX as u32 {
            return Err(HeaderError::Damaged(NetcdfError::NegativeCount { what }));
        }
        let left = self.file_len.saturating_sub(self.at as u64);
        if u64::from(n).saturating_mul(each) > left {
            return Err(HeaderError::Damaged(NetcdfError::CountTooLarge {
                what,
                count: n,
                file_len: self.file_len,
            }));
        }
        Ok(u64::from(n))
    }

    fn padding(&mut self, n: u64) -> Result<(), HeaderError> {
        self.take((4 - n % 4) % 4).map(drop)
    }

    fn name(&mut self) -> Result<String, HeaderError> {
        let n = self.count("name bytes", 1)?;
        let text = String::from_utf8_lossy(self.take(n)?).into_owned();
        self.padding(n)?;
        Ok(text)
    }

    /// A list header: its tag (or ABSENT: two zeros) and element count.
    fn list(&mut self, tag: u32, what: &'static str, each: u64) -> Result<u64, HeaderError> {
        let found = self.u32()?;
        let n = self.count(what, each)?;
        match found {
            0 if n == 0 => Ok(0),
            t if t == tag => Ok(n),
            found => Err(HeaderError::Damaged(NetcdfError::WrongTag {
                what,
                expected: tag,
                found,
            })),
        }
    }

    fn attributes(&mut self) -> Result<Vec<Attribute>, HeaderError> {
        let n = self.list(12, "attributes", 12)?;
        let mut out = Vec::with_capacity(n as usize);
        for _ in 0..n {
            let name = self.name()?;
            let kind = NcType::from_code(self.u32()?)?;
            let count = self.count("attribute values", kind.size())?;
            let bytes = count * kind.size();
            let raw = self.take(bytes)?;
            let value = match kind {
                NcType::Char => {
                    let text = String::from_utf8_lossy(raw);
                    Value::Text(text.trim_end_matches('\0').to_string())
                }
                _ => Value::Numbers(kind, numbers(kind, raw)),
            };
            self.padding(bytes)?;
            out.push(Attribute { name, value });
        }
        Ok(out)
    }
}

/// Big-endian values of type `kind` as f64.
fn numbers(kind: NcType, raw: &[u8]) -> Vec<f64> {
    raw.chunks_exact(kind.size() as usize)
        .map(|b| match kind {
            NcType::Byte | NcType::Char => f64::from(b[0] as i8),
            NcType::Short => f64::from(i16::from_be_bytes([b[0], b[1]])),
            NcType::Int => f64::from(i32::from_be_bytes([b[0], b[1], b[2], b[3]])),
            NcType::Float => f64::from(f32::from_be_bytes([b[0], b[1], b[2], b[3]])),
            NcType::Double => f64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        })
        .collect()
}

/// Parses the header at the start of `bytes` (the first bytes of a file of `file_len` bytes).
pub(crate) fn parse(bytes: &[u8], file_len: u64) -> Result<Header, HeaderError> {
    let mut cursor = Cursor {
        bytes,
        at: 0,
        file_len,
    };
    let magic = cursor.take(4).map_err(|e| match e {
        HeaderError::NeedMore => e,
        HeaderError::Damaged(_) => HeaderError::Damaged(NetcdfError::TooShort),
    })?;
    let offset_bytes = match magic {
        [b'C', b'D', b'F', 1] => 4,
        [b'C', b'D', b'F', 2] => 8,
        [b'C', b'D', b'F', 5] => {
            return Err(HeaderError::Damaged(NetcdfError::Cdf5));
        }
        [0x89, b'H', b'D', b'F'] => {
            return Err(HeaderError::Damaged(NetcdfError::Netcdf4));
        }
        _ => {
            return Err(HeaderError::Damaged(NetcdfError::NotNetcdf));
        }
    };
    let records = match cursor.u32()? {
        u32::MAX => None,
        n if n > i32::MAX as u32 => {
            return Err(HeaderError::Damaged(NetcdfError::NegativeRecords(n as i32)));
        }
        n => Some(u64::from(n)),
    };
    let n = cursor.list(10, "dimensions", 8)?;
    let mut dimensions = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let name = cursor.name()?;
        let len = cursor.u32()?;
        if len > i32::MAX as u32 {
            return Err(HeaderError::Damaged(NetcdfError::NegativeDimension(name)));
        }
        dimensions.push(Dimension {
            name,
            len: u64::from(len),
        });
    }
    let attributes = cursor.attributes()?;
    let n = cursor.list(11, "variables", 24)?;
    let mut variables = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let name = cursor.name()?;
        let rank = cursor.count("variable dimensions", 4)?;
        let mut ids = Vec::with_capacity(rank as usize);
        for _ in 0..rank {
            let id = cursor.u32()? as usize;
            if id >= dimensions.len() {
                return Err(HeaderError::Damaged(NetcdfError::UnknownDimension {
                    variable: name,
                    id,
                    count: dimensions.len(),
                }));
            }
            ids.push(id);
        }
        let var_attributes = cursor.attributes()?;
        let kind = NcType::from_code(cursor.u32()?)?;
        let _vsize = cursor.u32()?;
        let begin = if offset_bytes == 8 {
            let b = cursor.take(8)?;
            u64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
        } else {
            u64::from(cursor.u32()?)
        };
        variables.push(Variable {
            name,
            dimensions: ids,
            attributes: var_attributes,
            kind,
            begin,
        });
    }
    Ok(Header {
        records,
        dimensions,
        attributes,
        variables,
    })
}
