//! Whole CSV files made in memory through the csv crate (fields quoted
//! where they need it, one record a line), then written in one piece
//! ([`crate::write_atomic`]). Files appended a row at a time as a run
//! goes are [`crate::row_file`]'s.
use crate::error::Result;
use std::path::Path;

/// A CSV document being built.
pub struct CsvText(csv::Writer<Vec<u8>>);

impl Default for CsvText {
    fn default() -> Self {
        Self::new()
    }
}

impl CsvText {
    /// An empty document (rows may differ in length).
    pub fn new() -> Self {
        Self(
            csv::WriterBuilder::new()
                .flexible(true)
                .from_writer(Vec::new()),
        )
    }

    /// Append one record.
    pub fn row<I, F>(&mut self, fields: I) -> &mut Self
    where
        I: IntoIterator<Item = F>,
        F: AsRef<[u8]>,
    {
        // Into memory, with rows of any length allowed: nothing can fail.
        self.0.write_record(fields).expect("a CSV record in memory");
        self
    }

    /// The document's bytes.
    pub fn into_bytes(self) -> Vec<u8> {
        self.0.into_inner().expect("a CSV document in memory")
    }

    /// The document as text.
    pub fn into_string(self) -> String {
        String::from_utf8(self.into_bytes()).expect("CSV of UTF-8 fields")
    }

    /// Write the document to `path` (a temporary sibling renamed into place).
    pub fn write(self, path: &Path) -> Result<()> {
        crate::write_atomic(path, &self.into_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_quoted_only_where_needed() {
        let mut t = CsvText::new();
        t.row(["step", "frame"]).row(["0", "a,b.png"]).row(["1"]);
        assert_eq!(t.into_string(), "step,frame\n0,\"a,b.png\"\n1\n");
    }
}
