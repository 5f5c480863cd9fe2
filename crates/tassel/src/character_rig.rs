//! One kind of character compiled once: its skeleton and every solver's rig, shared by
//! any number of [`CharacterSim`](crate::CharacterSim)s through an [`Arc`](std::sync::Arc).

use crate::dynamics::chain::ChainRig;
use crate::dynamics::cloth::ClothRig;
use crate::dynamics::rope::Ropes;
use crate::dynamics::spring::SpringRig;
use crate::dynamics::vrm::{VrmOptions, VrmRig, VrmSpringBones};
use crate::dynamics::RigSettings;
use crate::error::{Error, Result};
use crate::skeleton::Skeleton;

/// A skeleton with its chains, springs, cloths, ropes and VRM spring bones compiled: the
/// read-only part of a character. Compile it once per kind of character and give each
/// character an `Arc` of it ([`CharacterSim::from_rig`](crate::CharacterSim::from_rig)).
///
/// ```
/// use std::sync::Arc;
/// use tassel::{builtin, CharacterRig, CharacterSim};
/// let c = builtin::character();
/// let rig = Arc::new(CharacterRig::new(c.skeleton.clone(), &c.rig).unwrap());
/// let a = CharacterSim::from_rig(rig.clone());
/// let b = CharacterSim::from_rig(rig.clone());
/// assert!(Arc::ptr_eq(a.rig(), b.rig()));
/// ```
#[derive(Debug, Clone)]
pub struct CharacterRig {
    pub(crate) skeleton: Skeleton,
    pub(crate) chains: ChainRig,
    pub(crate) springs: SpringRig,
    pub(crate) cloths: ClothRig,
    /// The ropes as compiled, before any frame: each character starts from a copy.
    pub(crate) ropes: Ropes,
    pub(crate) vrm: VrmRig,
    simulated: Vec<usize>,
}

impl CharacterRig {
    /// Compiles `rig` for `skeleton` (no VRM springs).
    pub fn new(skeleton: Skeleton, rig: &RigSettings) -> Result<Self> {
        Self::with_vrm(
            skeleton,
            rig,
            &VrmSpringBones::default(),
            VrmOptions::default(),
        )
    }

    /// Compiles `rig` and a model's VRM spring bones for `skeleton`. The VRM springs run
    /// first (on the animated pose), then chains, springs, cloths and ropes; a bone may
    /// belong to one solver only (an error names a bone claimed twice).
    pub fn with_vrm(
        skeleton: Skeleton,
        rig: &RigSettings,
        vrm: &VrmSpringBones,
        options: VrmOptions,
    ) -> Result<Self> {
        let vrm = VrmRig::new(&skeleton, vrm, options)?;
        let chains = ChainRig::new(&skeleton, rig)?;
        let springs = SpringRig::new(&skeleton, &rig.springs)?;
        let cloths = ClothRig::new(&skeleton, rig)?;
        rig.validate_for(&skeleton)?;
        let ropes = Ropes::new(&skeleton, rig)?;
        // One solver per bone, checked in one pass over an owner table (a rig may list
        // thousands of bones). A chain owns the joints it moves and the joints it turns
        // (its roots included); several chains may share a root, several cloths a bone.
        let mut owner: Vec<Option<&'static str>> = vec![None; skeleton.len()];
        let mut claim = |j: usize, who: &'static str| -> Result<()> {
            match owner[j] {
                Some(other) if other != who => Err(Error::InvalidParameter(format!(
                    "bone '{}' is simulated by a {other} and by a {who}; a bone belongs \
                     to one solver",
                    skeleton.name(j)
                ))),
                _ => {
                    owner[j] = Some(who);
                    Ok(())
                }
            }
        };
        for j in vrm.simulated_joints() {
            claim(j, "VRM spring")?;
        }
        for p in 0..chains.point_count() {
            let info = chains.point(p);
            if let (Some(j), Some(_)) = (info.joint, info.parent) {
                claim(j, "chain")?;
            }
        }
        for (j, _, _) in chains.rotating_joints() {
            claim(j, "chain")?;
        }
        for i in 0..springs.len() {
            claim(springs.joint(i), "spring")?;
        }
        // A cloth and a rope also turn their pinned first bones.
        for j in cloths.simulated_joints().chain(cloths.turned_joints()) {
            claim(j, "cloth")?;
        }
        for j in ropes.simulated_joints().chain(ropes.turned_joints()) {
            claim(j, "rope")?;
        }
        let mut simulated: Vec<usize> = (0..skeleton.len())
            .filter(|&j| owner[j].is_some())
            .collect();
        simulated.shrink_to_fit();
        Ok(Self {
            skeleton,
            chains,
            springs,
            cloths,
            ropes,
            vrm,
            simulated,
        })
    }

    /// The skeleton.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// The compiled chains.
    pub fn chains(&self) -> &ChainRig {
        &self.chains
    }

    /// The compiled springs.
    pub fn springs(&self) -> &SpringRig {
        &self.springs
    }

    /// The compiled cloths.
    pub fn cloths(&self) -> &ClothRig {
        &self.cloths
    }

    /// The compiled VRM spring bones.
    pub fn vrm(&self) -> &VrmRig {
        &self.vrm
    }

    /// Every joint a solver writes (VRM springs, chain joints that turn or move, springs,
    /// cloth and rope bones, the pinned first bones cloths and ropes turn), ascending, each once: the joints a bake must key and an
    /// engine must copy back. Computed once, at compile time.
    pub fn simulated_joints(&self) -> &[usize] {
        &self.simulated
    }

    /// The index of chain `name` (its `name` in the rig file), if there is one.
    pub fn chain_index(&self, name: &str) -> Option<usize> {
        (0..self.chains.chain_count()).find(|&i| self.chains.chain_settings(i).name == name)
    }
}
