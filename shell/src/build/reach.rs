//! What is reachable from the root: the only definitions whose plugins are
//! loaded and whose objects are created. The walk also refuses instancing
//! cycles and DAGs deeper than the hit stack.

use crate::desc::{Desc, Instance};
use crate::error::{ErrorKind, SceneError};
use rtk_kernel::HIT_STACK_DEPTH;
use std::collections::{BTreeSet, HashMap};

/// The definitions reachable from the root.
pub(crate) struct Reach {
    /// Object definitions, by name.
    pub objects: BTreeSet<String>,
    /// Shader definitions, by name.
    pub shaders: BTreeSet<String>,
    /// The first reachable instance with a transform (the instance-transform
    /// class is loaded only if there is one; errors point at it).
    pub first_transform: Option<Instance>,
}

/// The state of one walk.
struct Walk<'d> {
    desc: &'d Desc,
    reach: Reach,
    /// Levels each definition occupies (itself and below).
    depth: HashMap<String, usize>,
    /// Leaf instances each definition expands to (1 for a primitive; the
    /// sum over its children otherwise), in f64 so a doubling DAG of any
    /// depth cannot overflow the count.
    expansion: HashMap<String, f64>,
    /// The definitions on the current path, for cycle messages.
    path: Vec<String>,
}

impl Reach {
    /// Walk the DAG from the root.
    pub(crate) fn walk(desc: &Desc) -> Result<Reach, SceneError> {
        let mut w = Walk {
            desc,
            reach: Reach {
                objects: BTreeSet::new(),
                shaders: BTreeSet::new(),
                first_transform: None,
            },
            depth: HashMap::new(),
            expansion: HashMap::new(),
            path: Vec::new(),
        };
        let root = &desc.render.root;
        let d = w.visit(root, 0)?;
        if d > HIT_STACK_DEPTH {
            return Err(too_deep(root, &format!("{d} levels deep")));
        }
        let n = w.expansion.get(&root.object).copied().unwrap_or(1.0);
        let max = desc.render.max_instances as f64;
        if n > max {
            return Err(SceneError::new(
                ErrorKind::Invalid,
                &root.object_origin,
                &root.path,
                "object",
                format!(
                    "the object DAG expands to {n:.3e} instances of primitives, more than \
                     `[render] max_instances` ({max:.0}): a ray may have to visit each of them. \
                     Raise the limit if the scene's aggregates cull them"
                ),
            ));
        }
        Ok(w.reach)
    }
}

/// The error for a DAG deeper than the hit stack, at `inst`.
fn too_deep(inst: &Instance, how: &str) -> SceneError {
    SceneError::new(
        ErrorKind::Cycle,
        &inst.object_origin,
        &inst.path,
        "object",
        format!("the object DAG is {how} (transforms count as a level); rtk traces at most {HIT_STACK_DEPTH}"),
    )
}

impl Walk<'_> {
    /// Visit an instance `above` levels below the root; returns the number
    /// of levels it occupies. The walk stops as soon as a path is deeper
    /// than the hit stack, so its recursion is bounded by
    /// [`HIT_STACK_DEPTH`] whatever the scene (a chain of 20,000 instances
    /// is refused, not a stack overflow).
    fn visit(&mut self, inst: &Instance, above: usize) -> Result<usize, SceneError> {
        if let Some(s) = &inst.shader {
            self.reach.shaders.insert(s.clone());
        }
        let transform_level = usize::from(inst.transform.is_some());
        if inst.transform.is_some() && self.reach.first_transform.is_none() {
            self.reach.first_transform = Some(inst.clone());
        }
        if let Some(pos) = self.path.iter().position(|s| *s == inst.object) {
            let mut cycle = self.path[pos..].to_vec();
            cycle.push(inst.object.clone());
            return Err(SceneError::new(
                ErrorKind::Cycle,
                &inst.object_origin,
                &inst.path,
                "object",
                format!("instancing cycle: {}", cycle.join(" -> ")),
            ));
        }
        let here = above + transform_level + 1;
        if let Some(d) = self.depth.get(&inst.object) {
            if above + transform_level + d > HIT_STACK_DEPTH {
                return Err(too_deep(
                    inst,
                    &format!("more than {HIT_STACK_DEPTH} levels deep here"),
                ));
            }
            return Ok(d + transform_level);
        }
        if here > HIT_STACK_DEPTH {
            return Err(too_deep(
                inst,
                &format!("more than {HIT_STACK_DEPTH} levels deep here"),
            ));
        }
        self.reach.objects.insert(inst.object.clone());
        self.path.push(inst.object.clone());
        let desc = self.desc;
        let mut deepest = 0;
        for c in &desc.objects[&inst.object].children {
            deepest = deepest.max(self.visit(c, here)?);
        }
        self.path.pop();
        let children = &desc.objects[&inst.object].children;
        let expands = if children.is_empty() {
            1.0
        } else {
            children
                .iter()
                .map(|c| self.expansion.get(&c.object).copied().unwrap_or(1.0))
                .sum()
        };
        self.expansion.insert(inst.object.clone(), expands);
        let d = 1 + deepest;
        self.depth.insert(inst.object.clone(), d);
        Ok(d + transform_level)
    }
}
