//! Fixed-length arrays read exactly: too many entries refused as too few are.
//!
//! Serde reads a `[T; N]` by taking `N` items and leaving the rest to the format, and the
//! `toml` reader drops what is left: `axis = [0, 0, 1, "junk"]` would read as `[0, 0, 1]`.
//! A field marked `#[serde(deserialize_with = "exact")]` reads its arrays (inside `Spanned`,
//! `Option` and `Vec`, nested arrays included) in full, so that any other length gives serde's
//! `invalid length 4, expected an array of length 3` at the array's line.

use serde::Deserialize;
use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use std::fmt;
use std::marker::PhantomData;
use toml::Spanned;

/// A type that [`exact`] reads: `f64`, `[T; N]`, and `Spanned`, `Option` or `Vec` of one.
pub trait Exact<'de>: Sized {
    /// Reads `Self` from `d`, every array at exactly its length.
    fn exact<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error>;
}

/// Reads `T` with its arrays at exactly their lengths, for `#[serde(deserialize_with)]` (an
/// `Option` field also needs `#[serde(default)]`).
///
/// ```
/// use satsim_tree::io::exact;
/// #[derive(serde::Deserialize)]
/// struct Hinge {
///     #[serde(deserialize_with = "exact")]
///     axis: toml::Spanned<[f64; 3]>,
/// }
/// assert!(toml::from_str::<Hinge>("axis = [0, 0, 1]").is_ok());
/// let e = toml::from_str::<Hinge>("axis = [0, 0, 1, 2]").err().unwrap();
/// assert_eq!(e.message(), "invalid length 4, expected an array of length 3");
/// ```
pub fn exact<'de, D: Deserializer<'de>, T: Exact<'de>>(d: D) -> Result<T, D::Error> {
    T::exact(d)
}

/// `T` read through [`Exact`], where serde asks for a `Deserialize` type.
struct Read<T>(T);

impl<'de, T: Exact<'de>> Deserialize<'de> for Read<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        T::exact(d).map(Read)
    }
}

impl<'de> Exact<'de> for f64 {
    fn exact<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        f64::deserialize(d)
    }
}

impl<'de, T: Exact<'de>> Exact<'de> for Option<T> {
    fn exact<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Option::<Read<T>>::deserialize(d).map(|x| x.map(|Read(x)| x))
    }
}

impl<'de, T: Exact<'de>> Exact<'de> for Vec<T> {
    fn exact<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Vec::<Read<T>>::deserialize(d).map(|v| v.into_iter().map(|Read(x)| x).collect())
    }
}

impl<'de, T: Exact<'de>> Exact<'de> for Spanned<T> {
    fn exact<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = Spanned::<Read<T>>::deserialize(d)?;
        let span = s.span();
        Ok(Spanned::new(span, s.into_inner().0))
    }
}

impl<'de, T: Exact<'de>, const N: usize> Exact<'de> for [T; N] {
    fn exact<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_tuple(N, ArrayVisitor(PhantomData))
    }
}

/// Reads the first `N` items as `T` and counts the rest (of any type) without reading them.
struct ArrayVisitor<T, const N: usize>(PhantomData<T>);

impl<'de, T: Exact<'de>, const N: usize> Visitor<'de> for ArrayVisitor<T, N> {
    type Value = [T; N];

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "an array of length {N}")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
        let mut items = Vec::with_capacity(N);
        let mut len = 0;
        loop {
            let more = if len < N {
                seq.next_element::<Read<T>>()?.map(|Read(x)| items.push(x))
            } else {
                seq.next_element::<IgnoredAny>()?.map(drop)
            };
            if more.is_none() {
                break;
            }
            len += 1;
        }
        <[T; N]>::try_from(items)
            .ok()
            .filter(|_| len == N)
            .ok_or_else(|| de::Error::invalid_length(len, &self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    struct Fields {
        #[serde(default, deserialize_with = "exact")]
        rows: Option<Spanned<[[f64; 3]; 2]>>,
        #[serde(default, deserialize_with = "exact")]
        list: Vec<[f64; 2]>,
    }

    fn message(text: &str) -> String {
        toml::from_str::<Fields>(text)
            .unwrap_err()
            .message()
            .to_owned()
    }

    /// Rows and lists of arrays: every array at its own length, extras of any type counted.
    #[test]
    fn nested_arrays_read_at_exactly_their_lengths() {
        let f: Fields = toml::from_str("rows = [[1, 2, 3], [4, 5, 6]]\nlist = [[1, 2]]").unwrap();
        assert_eq!(
            *f.rows.unwrap().get_ref(),
            [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
        );
        assert_eq!(f.list, [[1.0, 2.0]]);
        let rows = "invalid length 3, expected an array of length 2";
        let entries = "invalid length 4, expected an array of length 3";
        assert_eq!(message("rows = [[1, 2, 3], [4, 5, 6], []]"), rows);
        assert_eq!(message("rows = [[1, 2, 3], [4, 5, 6, true]]"), entries);
        assert_eq!(
            message("rows = [[1, 2, 3], [4, 5]]"),
            "invalid length 2, expected an array of length 3"
        );
        assert_eq!(
            message("list = [[1, 2], [3, 4, 5]]"),
            "invalid length 3, expected an array of length 2"
        );
        assert_eq!(
            message("rows = [[1, \"x\", 3], [4, 5, 6]]"),
            "invalid type: string \"x\", expected f64"
        );
    }
}
