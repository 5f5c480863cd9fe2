//! Changing a level between frames: add, remove and move colliders, and the motion of the
//! frame that the controller reads (a platform carries what stands on it, a door pushes
//! what it closes on).
//!
//! A frame: [`Level::start_frame`], then [`Level::set_pose`] for each collider that moves,
//! then every character's `move_shape`. Moving a collider updates its BVH leaves in place
//! (parry's `Bvh::insert` on an existing leaf re-fits its ancestors): measured cheaper than
//! a rebuild for a few moving colliders among many (`cargo bench -p tassel --bench
//! controller`, `level_edit`).

use super::{build_prims, check_placement, leaf, Level, LevelCollider, Slot, MAX_PRIMS};
use crate::controller::narrow::{Prim, Separation};
use crate::error::{Error, Result};
use crate::math::Transform;
use glam::{Quat, Vec3};

impl Level {
    /// Adds `collider` and returns its id (ids are never reused). Errors as
    /// [`Level::new`]; the level is unchanged on error.
    pub fn add(&mut self, collider: LevelCollider) -> Result<usize> {
        check_placement(&collider)?;
        let mut built = Vec::new();
        build_prims(&collider, &mut built)?;
        if self.primitive_count() + built.len() > MAX_PRIMS || self.slots.len() >= u32::MAX as usize
        {
            return Err(Error::InvalidParameter(format!(
                "level collider '{}': the level is full",
                collider.name
            )));
        }
        let id = self.slots.len();
        let mut ids = Vec::with_capacity(built.len());
        for p in built {
            let k = match self.free.pop() {
                Some(k) => {
                    self.prims[k as usize] = p;
                    self.owner[k as usize] = id as u32;
                    self.groups[k as usize] = collider.groups;
                    k
                }
                None => {
                    self.prims.push(p);
                    self.owner.push(id as u32);
                    self.groups.push(collider.groups);
                    (self.prims.len() - 1) as u32
                }
            };
            self.bvh.insert(leaf(&self.prims[k as usize]), k);
            ids.push(k);
        }
        self.slots.push(Some(Slot {
            collider,
            prims: ids,
            from: None,
        }));
        self.live += 1;
        Ok(id)
    }

    /// Removes collider `id` and returns it; `None` if there is none. Characters standing
    /// on it fall from the next `move_shape` on.
    pub fn remove(&mut self, id: usize) -> Option<LevelCollider> {
        let slot = self.slots.get_mut(id)?.take()?;
        for &k in &slot.prims {
            self.bvh.remove(k);
            self.free.push(k);
            // A removed primitive is out of the BVH; its group bits are cleared so that
            // nothing could see it even if it were reached another way.
            self.groups[k as usize] = 0;
        }
        self.moved.retain(|&m| m as usize != id);
        self.live -= 1;
        Some(slot.collider)
    }

    /// Moves collider `id` to `position` and `rotation` (world). The first move after
    /// [`Level::start_frame`] remembers where it was, so that the controller sees its
    /// motion over the frame. Errors for a missing id or a non-finite pose.
    pub fn set_pose(&mut self, id: usize, position: Vec3, rotation: Quat) -> Result<()> {
        let Some(slot) = self.slots.get_mut(id).and_then(Option::as_mut) else {
            return Err(Error::InvalidParameter(format!(
                "level collider {id} does not exist"
            )));
        };
        // Placed in the collider itself (no copy of its shape, which may be a large
        // mesh), and put back if the new pose is refused.
        let was = (slot.collider.position, slot.collider.rotation);
        slot.collider.position = position;
        slot.collider.rotation = rotation;
        let mut built = Vec::with_capacity(slot.prims.len());
        if let Err(e) =
            check_placement(&slot.collider).and_then(|()| build_prims(&slot.collider, &mut built))
        {
            (slot.collider.position, slot.collider.rotation) = was;
            return Err(e);
        }
        debug_assert_eq!(built.len(), slot.prims.len());
        if slot.from.is_none() {
            slot.from = Some((was.0, was.1.normalize()));
            self.moved.push(id as u32);
        }
        for (&k, p) in slot.prims.iter().zip(built) {
            self.bvh.insert(leaf(&p), k);
            self.prims[k as usize] = p;
        }
        Ok(())
    }

    /// Starts a frame: forgets the motion of the last one. A collider not moved after this
    /// call is at rest for the controller. Call it once per frame before moving colliders.
    pub fn start_frame(&mut self) {
        for &id in &self.moved {
            if let Some(Some(slot)) = self.slots.get_mut(id as usize) {
                slot.from = None;
            }
        }
        self.moved.clear();
    }

    /// The motion of collider `id` since [`Level::start_frame`]: `(from, to)` poses (scale
    /// 1); `None` when it has not moved (or does not exist).
    pub fn motion(&self, id: usize) -> Option<(Transform, Transform)> {
        let slot = self.slot(id)?;
        let (p, r) = slot.from?;
        let c = &slot.collider;
        Some((
            Transform {
                translation: p,
                rotation: r,
                scale: Vec3::ONE,
            },
            Transform {
                translation: c.position,
                rotation: c.rotation.normalize(),
                scale: Vec3::ONE,
            },
        ))
    }

    /// The ids of the colliders moved since [`Level::start_frame`], in the order moved.
    pub fn moved(&self) -> impl Iterator<Item = usize> + '_ {
        self.moved.iter().map(|&id| id as usize)
    }

    /// The groups of collider `id` (0 when there is none).
    pub(crate) fn groups_of(&self, id: usize) -> u32 {
        self.slot(id).map_or(0, |s| s.collider.groups)
    }

    /// The nearest of collider `id`'s primitives to the capsule `a`–`b` of `radius`.
    pub(crate) fn separation_from(
        &self,
        id: usize,
        a: Vec3,
        b: Vec3,
        radius: f32,
    ) -> Option<Separation> {
        self.prims_of(id)
            .map(|p| p.separation(a, b, radius))
            .min_by(|x, y| x.distance.total_cmp(&y.distance))
    }

    /// The first contact of the capsule `a`–`b` of `radius` swept along `v` with collider
    /// `id` alone: the fraction of `v` and the contact.
    pub(crate) fn sweep_against(
        &self,
        id: usize,
        a: Vec3,
        b: Vec3,
        radius: f32,
        v: Vec3,
    ) -> Option<(f32, Separation)> {
        self.prims_of(id)
            .filter_map(|p| p.sweep(a, b, radius, v))
            .min_by(|x, y| x.0.total_cmp(&y.0))
    }

    fn prims_of(&self, id: usize) -> impl Iterator<Item = &Prim> + '_ {
        self.slot(id)
            .into_iter()
            .flat_map(|s| s.prims.iter().map(|&k| &self.prims[k as usize]))
    }
}
