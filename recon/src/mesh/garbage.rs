//! Garbage collection: removes deleted elements and renumbers the survivors (properties
//! follow their elements).

use super::handles::INVALID;
use super::SurfaceMesh;

fn kept(deleted: &[bool]) -> (Vec<usize>, Vec<u32>) {
    let mut keep = Vec::new();
    let mut map = vec![INVALID; deleted.len()];
    for (i, &d) in deleted.iter().enumerate() {
        if !d {
            map[i] = keep.len() as u32;
            keep.push(i);
        }
    }
    (keep, map)
}

fn remap(map: &[u32], i: u32) -> u32 {
    if i == INVALID {
        INVALID
    } else {
        map[i as usize]
    }
}

impl SurfaceMesh {
    /// Drops deleted vertices, edges and faces, compacting every array and property.
    /// Handles obtained before the call are invalid afterwards.
    pub fn garbage_collection(&mut self) {
        if !self.has_garbage() {
            return;
        }
        let (vkeep, vmap) = kept(&self.vdeleted);
        let (ekeep, emap) = kept(&self.edeleted);
        let (fkeep, fmap) = kept(&self.fdeleted);
        let hmap = |h: u32| {
            if h == INVALID {
                INVALID
            } else {
                let e = emap[(h >> 1) as usize];
                if e == INVALID {
                    INVALID
                } else {
                    (e << 1) | (h & 1)
                }
            }
        };
        self.points = vkeep.iter().map(|&i| self.points[i]).collect();
        self.vertex_out = vkeep.iter().map(|&i| hmap(self.vertex_out[i])).collect();
        let mut hconn = Vec::with_capacity(ekeep.len() * 2);
        for &e in &ekeep {
            for k in 0..2 {
                let mut c = self.hconn[2 * e + k];
                c.to = remap(&vmap, c.to);
                c.next = hmap(c.next);
                c.prev = hmap(c.prev);
                c.face = remap(&fmap, c.face);
                hconn.push(c);
            }
        }
        self.hconn = hconn;
        self.face_he = fkeep.iter().map(|&i| hmap(self.face_he[i])).collect();
        self.vdeleted = vec![false; vkeep.len()];
        self.edeleted = vec![false; ekeep.len()];
        self.fdeleted = vec![false; fkeep.len()];
        self.n_deleted = [0; 3];
        self.vertex_props.compact(&vkeep);
        self.edge_props.compact(&ekeep);
        self.face_props.compact(&fkeep);
    }
}
