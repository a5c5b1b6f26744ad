//! One results table, written both as a markdown table and as CSV, so a column's name and its cell
//! are declared once and the two files cannot drift apart (a CSV header one column off its
//! fields, a markdown column missing from the CSV).
//!
//! The two files need not hold the same columns: the markdown rounds for reading and the CSV keeps
//! digits for analysis, and some columns are only in one of them, so a column may give each file
//! its own name and cell, or appear in one file only. Cells are computed from the caller's rows
//! by the columns' closures, and the same table can write different row sets (all rows to the
//! CSV, one preset's to the markdown).

use std::fmt::Write as _;

/// How a column's markdown cells align.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// Text.
    Left,
    /// Numbers.
    Right,
}

/// How the markdown table is laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// Columns padded to their widest cell (comfy-table's ASCII markdown), right-aligned columns
    /// padded on the left.
    Padded,
    /// One space around each cell, alignment in the rule (`---:`).
    Compact,
}

type CellFn<'a, R> = Box<dyn Fn(&R) -> String + 'a>;

/// One column: its markdown name, its CSV name (either absent where the column is in one file
/// only) and its cell, with the CSV's own cell where the files format it apart.
struct Column<'a, R> {
    md: Option<String>,
    csv: Option<String>,
    cell: CellFn<'a, R>,
    csv_cell: Option<CellFn<'a, R>>,
    align: Align,
}

/// A table over rows of type `R` (see the module docs).
pub struct Table<'a, R> {
    style: Style,
    columns: Vec<Column<'a, R>>,
}

impl<'a, R> Table<'a, R> {
    /// An empty table whose markdown has `style`.
    pub fn new(style: Style) -> Self {
        Table {
            style,
            columns: Vec::new(),
        }
    }

    fn push(
        mut self,
        md: Option<&str>,
        csv: Option<&str>,
        align: Align,
        cell: CellFn<'a, R>,
        csv_cell: Option<CellFn<'a, R>>,
    ) -> Self {
        self.columns.push(Column {
            md: md.map(str::to_string),
            csv: csv.map(str::to_string),
            cell,
            csv_cell,
            align,
        });
        self
    }

    /// A column in both files with the same name and cell.
    pub fn col(self, name: &str, align: Align, cell: impl Fn(&R) -> String + 'a) -> Self {
        self.push(Some(name), Some(name), align, Box::new(cell), None)
    }

    /// A column in both files with the same cell under different names.
    pub fn renamed(
        self,
        md_name: &str,
        csv_name: &str,
        align: Align,
        cell: impl Fn(&R) -> String + 'a,
    ) -> Self {
        self.push(Some(md_name), Some(csv_name), align, Box::new(cell), None)
    }

    /// A column in both files, each with its own name and cell (the markdown's rounded, say).
    pub fn split(
        self,
        md_name: &str,
        align: Align,
        md_cell: impl Fn(&R) -> String + 'a,
        csv_name: &str,
        csv_cell: impl Fn(&R) -> String + 'a,
    ) -> Self {
        let csv_cell: CellFn<'a, R> = Box::new(csv_cell);
        self.push(
            Some(md_name),
            Some(csv_name),
            align,
            Box::new(md_cell),
            Some(csv_cell),
        )
    }

    /// A column in the markdown only.
    pub fn md(self, name: &str, align: Align, cell: impl Fn(&R) -> String + 'a) -> Self {
        self.push(Some(name), None, align, Box::new(cell), None)
    }

    /// A column in the CSV only.
    pub fn csv_only(self, name: &str, cell: impl Fn(&R) -> String + 'a) -> Self {
        self.push(None, Some(name), Align::Left, Box::new(cell), None)
    }

    /// The markdown table of `rows`, lines joined by newlines, no newline after the last.
    pub fn markdown<'r>(&self, rows: impl IntoIterator<Item = &'r R>) -> String
    where
        R: 'r,
    {
        let cols: Vec<&Column<R>> = self.columns.iter().filter(|c| c.md.is_some()).collect();
        let header = cols.iter().filter_map(|c| c.md.clone());
        let cells = |r: &R| -> Vec<String> { cols.iter().map(|c| (c.cell)(r)).collect() };
        match self.style {
            Style::Padded => {
                let mut t = comfy_table::Table::new();
                t.load_preset(comfy_table::presets::ASCII_MARKDOWN);
                t.set_header(header);
                for r in rows {
                    t.add_row(cells(r));
                }
                for (i, c) in cols.iter().enumerate() {
                    if let (Align::Right, Some(col)) = (c.align, t.column_mut(i)) {
                        col.set_cell_alignment(comfy_table::CellAlignment::Right);
                    }
                }
                t.to_string()
            }
            Style::Compact => {
                let mut s = format!("| {} |\n|", header.collect::<Vec<_>>().join(" | "));
                for c in &cols {
                    s.push_str(match c.align {
                        Align::Left => "---|",
                        Align::Right => "---:|",
                    });
                }
                for r in rows {
                    let _ = write!(s, "\n| {} |", cells(r).join(" | "));
                }
                s
            }
        }
    }

    /// The CSV of `rows`: the header line, then one line per row, each ending in a newline. Fields
    /// are written as the cells give them (the benches' names and numbers need no quoting).
    pub fn csv<'r>(&self, rows: impl IntoIterator<Item = &'r R>) -> String
    where
        R: 'r,
    {
        let cols: Vec<&Column<R>> = self.columns.iter().filter(|c| c.csv.is_some()).collect();
        let mut s = cols
            .iter()
            .filter_map(|c| c.csv.as_deref())
            .collect::<Vec<_>>()
            .join(",");
        s.push('\n');
        for r in rows {
            let fields: Vec<String> = cols
                .iter()
                .map(|c| quoted(c.csv_cell.as_ref().unwrap_or(&c.cell)(r)))
                .collect();
            s.push_str(&fields.join(","));
            s.push('\n');
        }
        s
    }
}

/// A CSV field as RFC 4180 writes it: in double quotes (inner quotes doubled) when it holds a
/// comma, a quote or a line break, else as it is.
fn quoted(field: String) -> String {
    if field.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table<'a>(style: Style) -> Table<'a, (&'a str, f64)> {
        Table::new(style)
            .col("name", Align::Left, |r: &(&str, f64)| r.0.to_string())
            .split(
                "ms",
                Align::Right,
                |r| format!("{:.1}", r.1),
                "time_ms",
                |r| format!("{:.3}", r.1),
            )
            .md("note", Align::Left, |_| "—".into())
            .csv_only("valid", |_| "true".into())
    }

    #[test]
    fn one_table_writes_both_files() {
        let rows = [("a", 1.25), ("bunny", 12.5)];
        assert_eq!(
            table(Style::Compact).markdown(&rows),
            "| name | ms | note |\n|---|---:|---|\n| a | 1.2 | — |\n| bunny | 12.5 | — |"
        );
        assert_eq!(
            table(Style::Padded).markdown(&rows),
            "| name  |   ms | note |\n|-------|------|------|\n| a     |  1.2 | —    |\n| bunny | 12.5 | —    |"
        );
        assert_eq!(
            table(Style::Padded).csv(&rows),
            "name,time_ms,valid\na,1.250,true\nbunny,12.500,true\n"
        );
        // A field with a comma or a quote is quoted, so the row keeps its columns.
        assert_eq!(
            table(Style::Compact).csv(&[("kmedoids, \"hops\"", 1.0)]),
            "name,time_ms,valid\n\"kmedoids, \"\"hops\"\"\",1.000,true\n"
        );
    }
}
