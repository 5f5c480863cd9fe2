//! A flat, depth-first skeleton: parents as `u16` indices with `parent[i] < i`, names and
//! a rest pose.

use crate::error::{Error, Result};
use crate::math::Transform;
use std::collections::HashMap;

/// Marks a joint without parent.
pub const NO_PARENT: u16 = u16::MAX;
pub use crate::limits::MAX_JOINTS;

/// Joints in depth-first order. Build it with [`Skeleton::new`] (already ordered) or
/// [`SkeletonBuilder`] (any order, sorted for you).
///
/// ```
/// use tassel::{Skeleton, Transform};
/// let sk = Skeleton::new(
///     vec!["root".into(), "tip".into()],
///     vec![None, Some(0)],
///     vec![Transform::IDENTITY; 2],
/// ).unwrap();
/// assert_eq!(sk.parent(1), Some(0));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    names: Vec<String>,
    parents: Vec<u16>,
    rest: Vec<Transform>,
    index: HashMap<String, u16>,
    /// Every joint once, by depth (roots first), skeleton order within a depth: parents
    /// before children, and joints next to each other independent of each other.
    level_order: Vec<u16>,
}

impl Skeleton {
    /// A skeleton from ordered parts: `parents[i]` must be `None` or less than `i`.
    pub fn new(
        names: Vec<String>,
        parents: Vec<Option<usize>>,
        rest: Vec<Transform>,
    ) -> Result<Self> {
        let n = names.len();
        if n == 0 {
            return Err(Error::EmptySkeleton);
        }
        if n > MAX_JOINTS {
            return Err(Error::TooManyJoints(n));
        }
        for (what, got) in [("parents", parents.len()), ("rest pose", rest.len())] {
            if got != n {
                return Err(Error::LengthMismatch {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        let mut index = HashMap::with_capacity(n);
        let mut packed = Vec::with_capacity(n);
        for (i, (name, parent)) in names.iter().zip(&parents).enumerate() {
            if index.insert(name.clone(), i as u16).is_some() {
                return Err(Error::DuplicateName(name.clone()));
            }
            match *parent {
                None => packed.push(NO_PARENT),
                Some(p) if p < i => packed.push(p as u16),
                Some(p) => {
                    return Err(Error::ParentOutOfOrder {
                        joint: i,
                        name: name.clone(),
                        parent: p,
                    })
                }
            }
            if !rest[i].is_finite() {
                return Err(Error::NonFinite(format!("rest pose of joint '{name}'")));
            }
            if !rest[i].within_limits() {
                return Err(Error::InvalidParameter(format!(
                    "rest pose of joint '{name}': translation {} or scale {} is beyond the \
                     limit of {:e}, or rotation {} is not a unit quaternion",
                    rest[i].translation,
                    rest[i].scale,
                    crate::limits::MAX_COORDINATE,
                    rest[i].rotation
                )));
            }
        }
        let mut depth = vec![0u16; n];
        for i in 0..n {
            if packed[i] != NO_PARENT {
                depth[i] = depth[packed[i] as usize] + 1;
            }
        }
        let mut level_order: Vec<u16> = (0..n as u16).collect();
        level_order.sort_by_key(|&i| depth[i as usize]);
        Ok(Self {
            names,
            parents: packed,
            rest,
            index,
            level_order,
        })
    }

    /// Every joint once, shallowest first (skeleton order within a depth): an order with
    /// every parent before its children in which neighbours do not depend on each other,
    /// so that a pass over it is not one long chain of dependent operations.
    pub(crate) fn level_order(&self) -> &[u16] {
        &self.level_order
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Always false: a skeleton has at least one joint.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The parent of joint `i`, if any.
    #[inline]
    pub fn parent(&self, i: usize) -> Option<usize> {
        match self.parents[i] {
            NO_PARENT => None,
            p => Some(p as usize),
        }
    }

    /// Raw parent indices ([`NO_PARENT`] for roots).
    pub fn parents(&self) -> &[u16] {
        &self.parents
    }

    /// Joint names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Name of joint `i` (panics past the last joint; see [`get_name`](Self::get_name)).
    pub fn name(&self, i: usize) -> &str {
        &self.names[i]
    }

    /// Name of joint `i`, or `None` past the last joint.
    pub fn get_name(&self, i: usize) -> Option<&str> {
        self.names.get(i).map(String::as_str)
    }

    /// The index of the joint called `name`.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.index.get(name).map(|&i| i as usize)
    }

    /// Local rest transforms.
    pub fn rest(&self) -> &[Transform] {
        &self.rest
    }

    /// The children of joint `i`, in order.
    pub fn children(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        (i + 1..self.len()).filter(move |&c| self.parents[c] as usize == i)
    }

    /// True when `joint` is `ancestor` or lies below it.
    pub fn is_descendant_of(&self, joint: usize, ancestor: usize) -> bool {
        let mut j = Some(joint);
        while let Some(k) = j {
            if k == ancestor {
                return true;
            }
            if k < ancestor {
                return false;
            }
            j = self.parent(k);
        }
        false
    }
}

/// Collects joints in any order (parents by builder index) and builds a depth-first
/// [`Skeleton`], rejecting cycles, missing parents, duplicate names and absurd sizes.
#[derive(Debug, Default, Clone)]
pub struct SkeletonBuilder {
    joints: Vec<(String, Option<usize>, Transform)>,
}

impl SkeletonBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a joint; `parent` is the builder index of another added joint. Returns this
    /// joint's builder index.
    pub fn add(
        &mut self,
        name: impl Into<String>,
        parent: Option<usize>,
        rest: Transform,
    ) -> usize {
        self.joints.push((name.into(), parent, rest));
        self.joints.len() - 1
    }

    /// Builds the skeleton. Returns it with `remap[builder_index] = skeleton_index`.
    pub fn build(self) -> Result<(Skeleton, Vec<usize>)> {
        let n = self.joints.len();
        if n == 0 {
            return Err(Error::EmptySkeleton);
        }
        if n > MAX_JOINTS {
            return Err(Error::TooManyJoints(n));
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut roots = Vec::new();
        for (i, (name, parent, _)) in self.joints.iter().enumerate() {
            match *parent {
                None => roots.push(i),
                Some(p) if p >= n => {
                    return Err(Error::MissingParent {
                        name: name.clone(),
                        parent: p,
                    })
                }
                Some(p) => children[p].push(i),
            }
        }
        // Depth-first from the roots; anything never reached lies on a cycle.
        let mut order = Vec::with_capacity(n);
        let mut stack: Vec<usize> = roots.into_iter().rev().collect();
        while let Some(j) = stack.pop() {
            order.push(j);
            stack.extend(children[j].iter().rev());
        }
        if order.len() != n {
            let mut seen = vec![false; n];
            for &j in &order {
                seen[j] = true;
            }
            let first = (0..n).find(|&j| !seen[j]).unwrap_or(0);
            return Err(Error::Cycle(self.joints[first].0.clone()));
        }
        let mut remap = vec![0usize; n];
        for (new, &old) in order.iter().enumerate() {
            remap[old] = new;
        }
        let mut names = Vec::with_capacity(n);
        let mut parents = Vec::with_capacity(n);
        let mut rest = Vec::with_capacity(n);
        for &old in &order {
            let (name, parent, t) = &self.joints[old];
            names.push(name.clone());
            parents.push(parent.map(|p| remap[p]));
            rest.push(*t);
        }
        Ok((Skeleton::new(names, parents, rest)?, remap))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t() -> Transform {
        Transform::IDENTITY
    }

    #[test]
    fn builder_sorts_depth_first() {
        let mut b = SkeletonBuilder::new();
        let c = b.add("child", Some(2), t());
        let r = b.add("root", None, t());
        let m = b.add("mid", Some(1), t());
        let (sk, remap) = b.build().unwrap();
        assert_eq!(sk.names(), &["root", "mid", "child"]);
        assert_eq!((remap[r], remap[m], remap[c]), (0, 1, 2));
        for i in 1..sk.len() {
            assert!(sk.parent(i).unwrap() < i);
        }
    }

    #[test]
    fn builder_rejects_bad_input() {
        let mut b = SkeletonBuilder::new();
        b.add("a", Some(1), t());
        b.add("b", Some(0), t());
        assert!(matches!(b.build(), Err(Error::Cycle(_))));

        let mut b = SkeletonBuilder::new();
        b.add("a", None, t());
        b.add("a", Some(0), t());
        assert_eq!(b.build().unwrap_err(), Error::DuplicateName("a".into()));

        let mut b = SkeletonBuilder::new();
        b.add("a", Some(9), t());
        assert!(matches!(b.build(), Err(Error::MissingParent { .. })));

        assert_eq!(
            SkeletonBuilder::new().build().unwrap_err(),
            Error::EmptySkeleton
        );
        let mut b = SkeletonBuilder::new();
        for i in 0..=MAX_JOINTS {
            b.add(format!("j{i}"), None, t());
        }
        assert!(matches!(b.build(), Err(Error::TooManyJoints(_))));
    }

    #[test]
    fn new_rejects_parent_out_of_order() {
        let e = Skeleton::new(
            vec!["a".into(), "b".into()],
            vec![Some(1), None],
            vec![t(); 2],
        )
        .unwrap_err();
        assert!(matches!(e, Error::ParentOutOfOrder { joint: 0, .. }));
        let mut bad = t();
        bad.translation.x = f32::NAN;
        assert!(matches!(
            Skeleton::new(vec!["a".into()], vec![None], vec![bad]),
            Err(Error::NonFinite(_))
        ));
    }
}
