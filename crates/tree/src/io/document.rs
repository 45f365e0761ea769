//! A TOML file parsed once ([`Document`]): every part of it that is read (the scene's own
//! keys, then each effect's section) deserializes from the one parsed tree, with the file's
//! spans, where each used to parse the whole text again. A scene with ten effect sections
//! parsed its text twelve times: 5.5 M instructions of the rigid deployment's 10.6 M scene
//! read (callgrind), which every run of a campaign pays.

use toml::Spanned;
use toml::de::{DeTable, DeValue, Deserializer, Error};

/// A TOML document's text and its parsed tree.
#[derive(Clone, Debug)]
pub struct Document<'a> {
    text: &'a str,
    root: Spanned<DeTable<'a>>,
}

impl<'a> Document<'a> {
    /// Parses `text`; the error is TOML's syntax error (with its span in `text`).
    pub fn parse(text: &'a str) -> Result<Self, Error> {
        Ok(Self {
            text,
            root: DeTable::parse(text)?,
        })
    }

    /// The document's text.
    pub fn text(&self) -> &'a str {
        self.text
    }

    /// A deserializer of the whole document, as `toml::from_str` would deserialize it.
    pub fn deserializer(&self) -> Deserializer<'a> {
        Deserializer::from(self.root.clone())
    }

    /// A deserializer of a document that holds only the value at the table keys `path`
    /// (and the tables on the way to it), each with its span and key as in the file: a
    /// deserializer that walks the document to `path` sees what it would see in the whole
    /// one, and errors name the same keys and lines, without copying the rest.
    pub fn only(&self, path: &[&str]) -> Deserializer<'a> {
        let span = self.root.span();
        Deserializer::from(Spanned::new(span, only(self.root.get_ref(), path)))
    }
}

/// The table `table` with only the entry at `path` (the first key's, itself cut down to the
/// rest of the path where it is a table).
fn only<'a>(table: &DeTable<'a>, path: &[&str]) -> DeTable<'a> {
    let mut kept = DeTable::new();
    let Some((first, rest)) = path.split_first() else {
        return kept;
    };
    if let Some((key, value)) = table.get_key_value(*first) {
        let value = match value.get_ref() {
            DeValue::Table(inner) if !rest.is_empty() => {
                Spanned::new(value.span(), DeValue::Table(only(inner, rest)))
            }
            _ => value.clone(),
        };
        kept.insert(key.clone(), value);
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Inner {
        x: f64,
    }

    #[derive(Debug, Deserialize, PartialEq)]
    struct Outer {
        a: Option<Inner>,
        b: Option<Spanned<Inner>>,
    }

    const TEXT: &str = "top = 1\n[a]\nx = 1.5\n[b]\nx = 2.5\n";

    #[test]
    fn the_whole_document_deserializes_as_from_str() {
        #[derive(Debug, Deserialize, PartialEq)]
        struct All {
            top: i64,
            a: Inner,
            b: Inner,
        }
        let doc = Document::parse(TEXT).unwrap();
        assert_eq!(
            All::deserialize(doc.deserializer()).unwrap(),
            toml::from_str::<All>(TEXT).unwrap()
        );
    }

    #[test]
    fn only_keeps_the_path_with_the_files_spans() {
        let doc = Document::parse(TEXT).unwrap();
        let o = Outer::deserialize(doc.only(&["b"])).unwrap();
        assert_eq!(o.a, None);
        let b = o.b.unwrap();
        assert_eq!(b.get_ref().x, 2.5);
        let whole = toml::from_str::<Outer>(TEXT).unwrap().b.unwrap();
        assert_eq!(b.span(), whole.span());
        // A path that is not there leaves an empty document.
        let none = Outer::deserialize(doc.only(&["c", "d"])).unwrap();
        assert_eq!((none.a, none.b), (None, None));
    }

    #[test]
    fn an_error_in_the_kept_part_names_the_same_key_and_span() {
        let text = "[a]\nx = 1.0\n[b]\nx = 1.0\ny = 2.0\n";
        let doc = Document::parse(text).unwrap();
        let cut = Outer::deserialize(doc.only(&["b"])).unwrap_err();
        let full = toml::from_str::<Outer>(text).unwrap_err();
        assert_eq!(cut.span(), full.span());
        assert_eq!(cut.message(), full.message());
        assert_eq!(
            crate::io::with_key(&cut, String::new()),
            crate::io::with_key(&full, String::new())
        );
    }

    #[test]
    fn a_syntax_error_is_tomls() {
        let text = "a = [1, 2\n";
        let e = Document::parse(text).unwrap_err();
        let t = text.parse::<toml::Table>().unwrap_err();
        assert_eq!((e.span(), e.message()), (t.span(), t.message()));
    }
}
