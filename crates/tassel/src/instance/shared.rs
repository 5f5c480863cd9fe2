//! Colliders shared between characters (KawaiiPhysics' shared collision, its master
//! branch after 1.21): one character's colliders, or a named `[[collider_group]]` of them,
//! placed in the world as its last frame posed them, handed to other characters whose
//! chains collide with them (`use_shared_collision`): a cape against another character's
//! body, hair against a held prop.

use super::CharacterSim;
use crate::collide::PlacedCollider;
use crate::error::Result;

impl CharacterSim {
    /// This character's colliders in the world as its last frame's animated pose and
    /// transform place them — every collider, or those of the rig's `[[collider_group]]`
    /// named `group` — appended to `out` (cleared first), for other characters'
    /// [`set_shared_colliders`](Self::set_shared_colliders). No allocation once `out` has
    /// grown. An error names a group the rig does not define.
    pub fn shared_colliders_into(
        &self,
        group: Option<&str>,
        out: &mut Vec<PlacedCollider>,
    ) -> Result<()> {
        out.clear();
        self.visit_shared_colliders(group, |c| out.push(c))?;
        Ok(())
    }

    /// Calls `f` with each collider [`shared_colliders_into`](Self::shared_colliders_into)
    /// gives, in order, without collecting them; returns how many there were.
    pub fn visit_shared_colliders(
        &self,
        group: Option<&str>,
        mut f: impl FnMut(PlacedCollider),
    ) -> Result<usize> {
        let chains = &self.rig.chains;
        let list = chains.shared_set(group)?;
        let models = self.animated_models();
        for &c in list {
            f(chains.colliders[c].place(&models, Some(&self.component)));
        }
        Ok(list.len())
    }

    /// [`shared_colliders_into`](Self::shared_colliders_into) into a new vector.
    pub fn shared_colliders(&self, group: Option<&str>) -> Result<Vec<PlacedCollider>> {
        let mut out = Vec::new();
        self.shared_colliders_into(group, &mut out)?;
        Ok(out)
    }

    /// Sets the colliders other characters share with this one (world space, as
    /// [`shared_colliders`](Self::shared_colliders) gives them), for the next frame and
    /// after until set again: the chains with `use_shared_collision = true` collide with
    /// them as with their own (swept against their motion since the last frame when their
    /// number stays the same; set them every frame for colliders that move). An error
    /// names a shape out of range or a transform that is not finite; nothing changes then.
    ///
    /// ```
    /// use tassel::{builtin, CharacterSim, Transform};
    /// let c = builtin::character();
    /// let (mut a, mut b) = (
    ///     CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap(),
    ///     CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap(),
    /// );
    /// let rest = c.skeleton.rest().to_vec();
    /// a.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
    /// // B's chains that use shared collision meet A's body next frame.
    /// b.set_shared_colliders(&a.shared_colliders(None).unwrap()).unwrap();
    /// b.frame(&rest, Transform::from_translation([0.3, 0.0, 0.0].into()), 0.0).unwrap();
    /// ```
    pub fn set_shared_colliders(&mut self, world: &[PlacedCollider]) -> Result<()> {
        let rig = std::sync::Arc::clone(&self.rig);
        self.state.set_shared_colliders(&rig.chains, world)
    }

    /// Drops the colliders shared with this character.
    pub fn clear_shared_colliders(&mut self) {
        let rig = std::sync::Arc::clone(&self.rig);
        // An empty set is always valid.
        let _ = self.state.set_shared_colliders(&rig.chains, &[]);
    }
}
