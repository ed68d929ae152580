//! Per-atom text columns (atom names, elements, residue names, chains, segments, types) stored
//! once per distinct value: each atom holds a 4-byte index into a table of the distinct strings.
//! A million-atom system has a few hundred distinct names, so a column costs 4 MB instead of the
//! ~56 MB of a `Vec<String>` (24-byte header plus a heap block per atom), and cloning a topology
//! copies indices, not strings.

use std::collections::HashMap;
use std::sync::Arc;

/// One text value per atom, interned (see the module docs).
#[derive(Clone, Default)]
pub struct Labels {
    /// Index into `values` of each atom's string.
    ids: Vec<u32>,
    /// The distinct strings, in the order they were first seen.
    values: Vec<Arc<str>>,
    /// Where each distinct string sits in `values`.
    lookup: HashMap<Arc<str>, u32>,
}

impl Labels {
    /// An empty column with room for `n` atoms.
    pub fn with_capacity(n: usize) -> Labels {
        Labels {
            ids: Vec::with_capacity(n),
            ..Labels::default()
        }
    }

    /// A column of `n` atoms that all hold `value`.
    pub fn filled(value: &str, n: usize) -> Labels {
        let mut labels = Labels::default();
        labels.push_repeated(value, n);
        labels
    }

    /// Number of atoms.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when the column holds no atom.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// The index of `value` in the table of distinct strings, added when new.
    pub fn intern(&mut self, value: &str) -> u32 {
        if let Some(&id) = self.lookup.get(value) {
            return id;
        }
        let id = self.values.len() as u32;
        let shared: Arc<str> = Arc::from(value);
        self.values.push(shared.clone());
        self.lookup.insert(shared, id);
        id
    }

    /// The index of `value` in the table of distinct strings, if some atom holds it (or held
    /// it: values are never removed).
    pub fn find(&self, value: &str) -> Option<u32> {
        self.lookup.get(value).copied()
    }

    /// Appends one atom's value.
    pub fn push(&mut self, value: impl AsRef<str>) {
        let id = self.intern(value.as_ref());
        self.ids.push(id);
    }

    /// Appends one atom whose value is the distinct string `id` (from [`Labels::intern`]).
    pub fn push_id(&mut self, id: u32) {
        assert!(
            (id as usize) < self.values.len(),
            "label id {id} out of range"
        );
        self.ids.push(id);
    }

    /// Appends atoms whose values are the distinct strings `ids` (from [`Labels::intern`]).
    pub fn extend_ids(&mut self, ids: &[u32]) {
        let known = self.values.len() as u32;
        assert!(
            ids.iter().all(|&id| id < known),
            "label id out of range ({known} values)"
        );
        self.ids.extend_from_slice(ids);
    }

    /// Appends one atom with the value of atom `i` (no lookup: for runs of equal values).
    pub fn push_like(&mut self, i: usize) {
        self.ids.push(self.ids[i]);
    }

    /// Appends `count` atoms with the same value.
    pub fn push_repeated(&mut self, value: &str, count: usize) {
        let id = self.intern(value);
        self.ids.resize(self.ids.len() + count, id);
    }

    /// Atom `i`'s value, or `None` past the end.
    pub fn get(&self, i: usize) -> Option<&str> {
        self.ids.get(i).map(|&id| &*self.values[id as usize])
    }

    /// Sets atom `i`'s value (panics past the end, like slice indexing).
    pub fn set(&mut self, i: usize, value: impl AsRef<str>) {
        let id = self.intern(value.as_ref());
        self.ids[i] = id;
    }

    /// The index of atom `i`'s value in the table of distinct strings (see [`Labels::distinct`]).
    pub fn id(&self, i: usize) -> u32 {
        self.ids[i]
    }

    /// Sets atom `i`'s value to the distinct string `id` (from [`Labels::intern`]).
    pub fn set_id(&mut self, i: usize, id: u32) {
        assert!(
            (id as usize) < self.values.len(),
            "label id {id} out of range"
        );
        self.ids[i] = id;
    }

    /// Sets every atom's value to `value`.
    pub fn fill(&mut self, value: &str) {
        let id = self.intern(value);
        self.ids.iter_mut().for_each(|x| *x = id);
    }

    /// Shortens the column to `n` atoms or pads it with `value`.
    pub fn resize(&mut self, n: usize, value: &str) {
        if n <= self.ids.len() {
            self.ids.truncate(n);
        } else {
            self.push_repeated(value, n - self.ids.len());
        }
    }

    /// Appends the values of atoms `range` of `other`.
    pub fn extend_from(&mut self, other: &Labels, range: std::ops::Range<usize>) {
        for i in range {
            self.push(&other[i]);
        }
    }

    /// The values of every atom, in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &str> + Clone + '_ {
        self.ids.iter().map(|&id| &*self.values[id as usize])
    }

    /// The distinct values (each once, in first-seen order) and, per atom, its index among
    /// them: per-value work (matching a selection pattern, guessing an element) is then done
    /// once per distinct value instead of once per atom.
    pub fn distinct(&self) -> (&[Arc<str>], &[u32]) {
        (&self.values, &self.ids)
    }

    /// The values as owned strings (for code that needs a `Vec<String>`).
    pub fn to_strings(&self) -> Vec<String> {
        self.iter().map(str::to_string).collect()
    }
}

impl std::ops::Index<usize> for Labels {
    type Output = str;

    fn index(&self, i: usize) -> &str {
        &self.values[self.ids[i] as usize]
    }
}

impl PartialEq for Labels {
    fn eq(&self, other: &Labels) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl<S: AsRef<str>> PartialEq<Vec<S>> for Labels {
    fn eq(&self, other: &Vec<S>) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter().map(AsRef::as_ref))
    }
}

impl std::fmt::Debug for Labels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<S: AsRef<str>> FromIterator<S> for Labels {
    fn from_iter<T: IntoIterator<Item = S>>(iter: T) -> Labels {
        let mut labels = Labels::default();
        for s in iter {
            labels.push(s.as_ref());
        }
        labels
    }
}

impl From<Vec<String>> for Labels {
    fn from(values: Vec<String>) -> Labels {
        values.iter().collect()
    }
}

impl From<Vec<&str>> for Labels {
    fn from(values: Vec<&str>) -> Labels {
        values.into_iter().collect()
    }
}

impl<'a> IntoIterator for &'a Labels {
    type Item = &'a str;
    type IntoIter = Box<dyn ExactSizeIterator<Item = &'a str> + 'a>;

    fn into_iter(self) -> Self::IntoIter {
        Box::new(self.iter())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_stored_once_and_read_back_in_order() {
        let mut l = Labels::default();
        for s in ["CA", "N", "CA", "O", "CA"] {
            l.push(s);
        }
        assert_eq!(l.len(), 5);
        assert_eq!(l.iter().collect::<Vec<_>>(), ["CA", "N", "CA", "O", "CA"]);
        let (values, ids) = l.distinct();
        assert_eq!(values.len(), 3);
        assert_eq!(ids, &[0, 1, 0, 2, 0]);
        assert_eq!(&l[3], "O");
        assert_eq!(l.get(5), None);
    }

    #[test]
    fn set_resize_and_fill_change_only_what_they_name() {
        let mut l = Labels::from(vec!["a", "b"]);
        l.set(0, "c");
        l.resize(4, "z");
        assert_eq!(l.to_strings(), ["c", "b", "z", "z"]);
        l.resize(1, "");
        assert_eq!(l.to_strings(), ["c"]);
        l.fill("");
        assert_eq!(l, Labels::from(vec![""]));
        assert_ne!(l, Labels::from(vec!["c"]));
    }
}
