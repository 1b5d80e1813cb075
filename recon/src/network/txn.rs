//! Transactions: every tool applies fully or not at all (the FIRES thesis, ch. 5, leaves
//! this unspecified; transactional tools and undo/redo are our design, docs/network.md).
//!
//! While a transaction is open every slot write records the slot's previous value. Rolling back restores
//! the old values in reverse order and truncates the arenas to their lengths at the start, which gives
//! back the network bit for bit. Committing turns the log into a [`Transaction`] holding the slot values
//! before and after, which is what undo and redo replay.

use super::handles::{EdgeId, FaceId, PolylineId, VertexId};
use super::mesh::{Edge, Face, Network, Polyline, Vertex};

/// One slot write: the slot and the value it held (before) or holds (after).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Change {
    Vertex(VertexId, Option<Vertex>),
    Edge(EdgeId, Option<Edge>),
    Face(FaceId, Option<Face>),
    Polyline(PolylineId, Option<Polyline>),
}

/// The open transaction's log.
#[derive(Clone, Debug, Default)]
pub(crate) struct Log {
    pub(crate) changes: Vec<Change>,
    pub(crate) lens: [usize; 4],
}

/// A committed transaction: enough to undo and redo it.
#[derive(Clone, Debug, PartialEq)]
pub struct Transaction {
    before: Vec<Change>,
    after: Vec<Change>,
    lens_before: [usize; 4],
    lens_after: [usize; 4],
}

impl Network {
    fn lens(&self) -> [usize; 4] {
        [
            self.vertices.len(),
            self.edges.len(),
            self.faces.len(),
            self.polylines.len(),
        ]
    }

    fn truncate_to(&mut self, lens: [usize; 4]) {
        self.vertices.resize(lens[0], None);
        self.edges.resize(lens[1], None);
        self.faces.resize(lens[2], None);
        self.polylines.resize(lens[3], None);
        self.boxes.truncate(lens[3]);
    }

    fn write_raw(&mut self, c: Change) {
        match c {
            Change::Vertex(id, v) => self.vertices[id.idx()] = v,
            Change::Edge(id, v) => {
                self.edges[id.idx()] = v;
                self.slot_written(Change::Edge(id, None));
            }
            Change::Face(id, v) => self.faces[id.idx()] = v,
            Change::Polyline(id, v) => {
                self.polylines[id.idx()] = v;
                self.slot_written(Change::Polyline(id, None));
            }
        }
    }

    fn current(&self, c: &Change) -> Change {
        match c {
            Change::Vertex(id, _) => Change::Vertex(*id, self.vertices[id.idx()].clone()),
            Change::Edge(id, _) => Change::Edge(*id, self.edges[id.idx()].clone()),
            Change::Face(id, _) => Change::Face(*id, self.faces[id.idx()].clone()),
            Change::Polyline(id, _) => Change::Polyline(*id, self.polylines[id.idx()].clone()),
        }
    }

    /// Opens a transaction (tools call this; transactions do not nest).
    pub(crate) fn begin(&mut self) {
        self.log = Some(Log {
            changes: Vec::new(),
            lens: self.lens(),
        });
    }

    /// Restores the network as it was at [`Network::begin`].
    pub(crate) fn rollback(&mut self) {
        if let Some(log) = self.log.take() {
            for c in log.changes.into_iter().rev() {
                self.write_raw(c);
            }
            self.truncate_to(log.lens);
        }
    }

    /// Closes the transaction and returns it.
    pub(crate) fn commit(&mut self) -> Transaction {
        let log = self.log.take().unwrap_or_default();
        // Keep the first recorded old value of each slot (the value before the transaction).
        let mut seen = std::collections::HashSet::new();
        let mut before = Vec::new();
        for c in log.changes {
            let key = match &c {
                Change::Vertex(id, _) => (0, id.0),
                Change::Edge(id, _) => (1, id.0),
                Change::Face(id, _) => (2, id.0),
                Change::Polyline(id, _) => (3, id.0),
            };
            if seen.insert(key) {
                before.push(c);
            }
        }
        let after = before.iter().map(|c| self.current(c)).collect();
        Transaction {
            before,
            after,
            lens_before: log.lens,
            lens_after: self.lens(),
        }
    }

    /// Runs `tool` as a transaction: on `Err` the network is restored bit for bit.
    pub(crate) fn transact<T, E>(
        &mut self,
        tool: impl FnOnce(&mut Network) -> Result<T, E>,
    ) -> Result<(T, Transaction), E> {
        self.begin();
        match tool(self) {
            Ok(v) => Ok((v, self.commit())),
            Err(e) => {
                self.rollback();
                Err(e)
            }
        }
    }

    /// Undoes a committed transaction (it must be the last one applied that is not undone).
    pub fn undo(&mut self, t: &Transaction) {
        for c in t.before.iter().rev() {
            self.write_raw(c.clone());
        }
        self.truncate_to(t.lens_before);
    }

    /// Re-applies an undone transaction.
    pub fn redo(&mut self, t: &Transaction) {
        self.truncate_to(t.lens_after);
        for c in &t.after {
            self.write_raw(c.clone());
        }
    }
}
