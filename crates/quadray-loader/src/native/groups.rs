//! The scene graph: `[[group]]`s of shapes, groups and instances placed by one transform, and
//! `[[instance]]`s that place a named group or shape again.
//!
//! Every group, and every named shape some instance places, becomes one
//! [`quadray::Prototype`], built once however often it is placed: loading costs what the file
//! holds, not what its instances expand to. Prototypes are pushed children first, the order the
//! core requires; a group that reaches itself through its instances is an error naming the cycle.

use super::*;
use crate::reach::PrototypeBoxes;
use quadray::{Instance, MAX_NESTING, Prototype};
use std::collections::HashSet;

/// A named definition an instance can place.
#[derive(Clone, Copy)]
pub(super) enum Def<'f> {
    Group(&'f Spanned<GroupSpec>),
    Sphere(&'f Spanned<SphereSpec>),
    Quadric(&'f Spanned<QuadricSpec>),
    Mesh(&'f Spanned<MeshSpec>),
}

/// The shapes, groups and instances of the world or of one group, with the key they are read at.
#[derive(Clone)]
pub(super) struct Contents<'f> {
    pub(super) key: String,
    pub(super) spheres: &'f [Spanned<SphereSpec>],
    pub(super) sphere_sets: &'f [Spanned<SphereSetSpec>],
    pub(super) planes: &'f [Spanned<PlaneSpec>],
    pub(super) quadrics: &'f [Spanned<QuadricSpec>],
    pub(super) meshes: &'f [Spanned<MeshSpec>],
    pub(super) groups: &'f [Spanned<GroupSpec>],
    pub(super) instances: &'f [Spanned<InstanceSpec>],
}

impl<'f> Contents<'f> {
    /// The world's contents: the file's top-level tables.
    pub(super) fn world(file: &'f SceneFile) -> Contents<'f> {
        Contents {
            key: String::new(),
            spheres: &file.spheres,
            sphere_sets: &file.sphere_sets,
            planes: &file.planes,
            quadrics: &file.quadrics,
            meshes: &file.meshes,
            groups: &file.groups,
            instances: &file.instances,
        }
    }

    fn group(g: &'f GroupSpec, key: String) -> Contents<'f> {
        Contents {
            key: format!("{key}."),
            spheres: &g.spheres,
            sphere_sets: &g.sphere_sets,
            planes: &g.planes,
            quadrics: &g.quadrics,
            meshes: &g.meshes,
            groups: &g.groups,
            instances: &g.instances,
        }
    }
}

/// What the build of the scene graph accumulates.
pub(super) struct GraphState<'f> {
    /// Every named group and shape, with the key it was defined at.
    defs: HashMap<String, (Def<'f>, String)>,
    /// Names some instance places.
    referenced: HashSet<String>,
    /// Prototype index of each definition built so far.
    built: HashMap<String, u32>,
    /// Definitions being built, outermost first: a name met again here closes a cycle.
    visiting: Vec<String>,
    /// The prototypes, children before parents.
    pub(super) prototypes: Vec<Prototype>,
    /// Their boxes, for the reach of what the world places.
    prototype_boxes: PrototypeBoxes,
    /// Per prototype, the most instances on a path down from it (0 for plain shapes).
    depths: Vec<usize>,
    /// Materials: the scene's own, then those of imported files.
    pub(super) materials: Vec<Material>,
    /// Their names.
    pub(super) material_names: Vec<String>,
    /// Notes for the user.
    pub(super) notes: Vec<String>,
    /// Materials made for `[[spheres]]` vertex colours, by base material and colour bits.
    pub(super) tinted: HashMap<(u32, [u32; 3]), u32>,
}

impl Builder<'_> {
    /// Collects every named definition (one namespace for groups and shapes, at any depth) and
    /// every name an instance refers to.
    pub(super) fn graph<'f>(
        &self,
        world: &Contents<'f>,
        materials: Vec<Material>,
        material_names: Vec<String>,
    ) -> Result<GraphState<'f>, LoadError> {
        let mut st = GraphState {
            defs: HashMap::new(),
            referenced: HashSet::new(),
            built: HashMap::new(),
            visiting: Vec::new(),
            prototypes: Vec::new(),
            prototype_boxes: PrototypeBoxes::default(),
            depths: Vec::new(),
            materials,
            material_names,
            notes: Vec::new(),
            tinted: HashMap::new(),
        };
        let mut todo = vec![world.clone()];
        while let Some(c) = todo.pop() {
            let defs = &mut st.defs;
            for (i, s) in c.spheres.iter().enumerate() {
                let key = format!("{}sphere[{i}]", c.key);
                self.define(defs, &s.get_ref().name, Def::Sphere(s), key)?;
            }
            for (i, q) in c.quadrics.iter().enumerate() {
                let key = format!("{}quadric[{i}]", c.key);
                self.define(defs, &q.get_ref().name, Def::Quadric(q), key)?;
            }
            for (i, m) in c.meshes.iter().enumerate() {
                let key = format!("{}mesh[{i}]", c.key);
                self.define(defs, &m.get_ref().name, Def::Mesh(m), key)?;
            }
            for inst in c.instances {
                st.referenced.insert(inst.get_ref().of.get_ref().clone());
            }
            for (i, g) in c.groups.iter().enumerate() {
                let key = format!("{}group[{i}]", c.key);
                self.define(
                    &mut st.defs,
                    &Some(g.get_ref().name.clone()),
                    Def::Group(g),
                    key.clone(),
                )?;
                todo.push(Contents::group(g.get_ref(), key));
            }
        }
        Ok(st)
    }

    fn define<'f>(
        &self,
        defs: &mut HashMap<String, (Def<'f>, String)>,
        name: &Option<Spanned<String>>,
        def: Def<'f>,
        key: String,
    ) -> Result<(), LoadError> {
        let Some(name) = name else { return Ok(()) };
        if let Some((_, first)) = defs.get(name.get_ref()) {
            return Err(self.err(
                name.span(),
                format!("{key}.name"),
                format!("\"{}\" is already the name of {first}", name.get_ref()),
            ));
        }
        defs.insert(name.get_ref().clone(), (def, key));
        Ok(())
    }

    /// Builds `c` into `out` (a prototype, or the world's shapes); `planes` receives planes, and
    /// is `None` inside a group (a plane is unbounded: it cannot be placed by an instance).
    pub(super) fn fill<'f>(
        &self,
        st: &mut GraphState<'f>,
        names: &HashMap<String, u32>,
        c: &Contents<'f>,
        out: &mut Prototype,
        mut planes: Option<&mut Vec<Plane>>,
    ) -> Result<(), LoadError> {
        let k = &c.key;
        for (i, s) in c.spheres.iter().enumerate() {
            let key = format!("{k}sphere[{i}]");
            if self.place_named(
                st,
                names,
                &s.get_ref().name,
                &s.get_ref().transform,
                (&key, k.is_empty()),
                out,
            )? {
                continue;
            }
            let mark = Mark::of(out);
            self.sphere(s, &key, names, false, out)?;
            if k.is_empty() {
                let placed = (s.span(), s.get_ref().transform.as_ref());
                self.world_within_limit(st, out, &mark, placed, (&key, "the shape"))?;
            }
        }
        for (i, s) in c.sphere_sets.iter().enumerate() {
            let key = format!("{k}spheres[{i}]");
            let mark = Mark::of(out);
            self.sphere_set(st, names, s, &key, out)?;
            if k.is_empty() {
                let placed = (s.span(), s.get_ref().transform.as_ref());
                self.world_within_limit(st, out, &mark, placed, (&key, "the spheres"))?;
            }
        }
        for (i, p) in c.planes.iter().enumerate() {
            let key = format!("{k}plane[{i}]");
            let Some(planes) = planes.as_deref_mut() else {
                return Err(self.err(
                    p.span(),
                    key,
                    "a plane is unbounded and cannot be in a group; put it in the world",
                ));
            };
            planes.push(self.plane(p, &key, names)?);
        }
        for (i, q) in c.quadrics.iter().enumerate() {
            let key = format!("{k}quadric[{i}]");
            if self.place_named(
                st,
                names,
                &q.get_ref().name,
                &q.get_ref().transform,
                (&key, k.is_empty()),
                out,
            )? {
                continue;
            }
            let mark = Mark::of(out);
            out.quadrics.push(self.quadric(q, &key, names)?);
            if k.is_empty() {
                let placed = (q.span(), q.get_ref().transform.as_ref());
                self.world_within_limit(st, out, &mark, placed, (&key, "the shape"))?;
            }
        }
        for (i, m) in c.meshes.iter().enumerate() {
            let key = format!("{k}mesh[{i}]");
            if self.place_named(
                st,
                names,
                &m.get_ref().name,
                &m.get_ref().transform,
                (&key, k.is_empty()),
                out,
            )? {
                continue;
            }
            let mark = Mark::of(out);
            self.mesh_into(st, names, m, &key, out, planes.as_deref_mut())?;
            if k.is_empty() {
                let placed = (m.span(), m.get_ref().transform.as_ref());
                self.world_within_limit(st, out, &mark, placed, (&key, "the mesh"))?;
            }
        }
        self.fill_instances(st, names, c, out)
    }

    /// [`Builder::placed_within_limit`] for what the world's `out` holds past `mark`, with the
    /// scene graph's prototypes.
    fn world_within_limit(
        &self,
        st: &mut GraphState<'_>,
        out: &Prototype,
        mark: &Mark,
        placed: (Range<usize>, Option<&Spanned<TransformSpec>>),
        key_and_what: (&str, &str),
    ) -> Result<(), LoadError> {
        let prototypes = (st.prototypes.as_slice(), &mut st.prototype_boxes);
        self.placed_within_limit((out, mark), prototypes, placed, key_and_what)
    }

    /// The instances `c` holds into `out`: its groups (built, and placed unless templates) and
    /// its instances of named prototypes.
    fn fill_instances<'f>(
        &self,
        st: &mut GraphState<'f>,
        names: &HashMap<String, u32>,
        c: &Contents<'f>,
        out: &mut Prototype,
    ) -> Result<(), LoadError> {
        let k = &c.key;
        for (i, g) in c.groups.iter().enumerate() {
            let key = format!("{k}group[{i}]");
            let spec = g.get_ref();
            // A template is built (so its errors show) but placed only by instances.
            let prototype =
                self.prototype(st, names, spec.name.get_ref(), spec.name.span(), &key)?;
            if spec.template.as_ref().is_some_and(|t| *t.get_ref()) {
                continue;
            }
            let transform = self.transform(&spec.transform, &format!("{key}.transform"))?;
            let mark = Mark::of(out);
            out.instances.push(Instance::new(prototype, transform));
            if k.is_empty() {
                let placed = (g.span(), spec.transform.as_ref());
                let what = format!("group \"{}\"", spec.name.get_ref());
                self.world_within_limit(st, out, &mark, placed, (&key, &what))?;
            }
        }
        for (i, inst) in c.instances.iter().enumerate() {
            let key = format!("{k}instance[{i}]");
            let spec = inst.get_ref();
            let prototype = self.prototype(
                st,
                names,
                spec.of.get_ref(),
                spec.of.span(),
                &format!("{key}.of"),
            )?;
            let transform = self.transform(&spec.transform, &format!("{key}.transform"))?;
            let material = spec
                .material
                .as_ref()
                .map(|m| self.material_id(names, m, &format!("{key}.material")))
                .transpose()?;
            let mark = Mark::of(out);
            out.instances.push(Instance {
                prototype,
                transform,
                material,
            });
            if k.is_empty() {
                let placed = (inst.span(), spec.transform.as_ref());
                let what = format!("\"{}\"", spec.of.get_ref());
                self.world_within_limit(st, out, &mark, placed, (&key, &what))?;
            }
        }
        Ok(())
    }

    /// A named shape some instance places is itself placed as an instance of its prototype (so
    /// it is stored once); returns whether it was. `key` is the shape's, and `in_world` whether
    /// `out` is the world's.
    fn place_named<'f>(
        &self,
        st: &mut GraphState<'f>,
        names: &HashMap<String, u32>,
        name: &Option<Spanned<String>>,
        transform: &Option<Spanned<TransformSpec>>,
        (key, in_world): (&str, bool),
        out: &mut Prototype,
    ) -> Result<bool, LoadError> {
        let Some(name) = name
            .as_ref()
            .filter(|n| st.referenced.contains(n.get_ref()))
        else {
            return Ok(false);
        };
        let prototype = self.prototype(st, names, name.get_ref(), name.span(), key)?;
        let placed = self.transform(transform, &format!("{key}.transform"))?;
        let mark = Mark::of(out);
        out.instances.push(Instance::new(prototype, placed));
        if in_world {
            let placed = (name.span(), transform.as_ref());
            self.world_within_limit(st, out, &mark, placed, (key, "the shape"))?;
        }
        Ok(true)
    }

    /// The prototype of definition `name` (referred to at `span`), built on first use.
    fn prototype<'f>(
        &self,
        st: &mut GraphState<'f>,
        names: &HashMap<String, u32>,
        name: &str,
        span: Range<usize>,
        at_key: &str,
    ) -> Result<u32, LoadError> {
        if let Some(&p) = st.built.get(name) {
            return Ok(p);
        }
        let Some(&(def, ref key)) = st.defs.get(name) else {
            let mut known: Vec<&str> = st.defs.keys().map(String::as_str).collect();
            known.sort_unstable();
            return Err(self.err(
                span,
                at_key,
                format!(
                    "no group or named shape \"{name}\" (defined: {}){}",
                    if known.is_empty() {
                        "none".into()
                    } else {
                        known.join(", ")
                    },
                    did_you_mean(name, known.iter().copied())
                ),
            ));
        };
        let key = key.clone();
        if let Some(start) = st.visiting.iter().position(|v| v == name) {
            let mut cycle: Vec<String> = st.visiting[start..]
                .iter()
                .map(|n| format!("\"{n}\""))
                .collect();
            cycle.push(format!("\"{name}\""));
            return Err(self.err(
                span,
                key,
                format!("groups place each other in a cycle: {}", cycle.join(" -> ")),
            ));
        }
        if st.visiting.len() >= MAX_NESTING {
            return Err(self.err(
                span,
                key,
                format!("groups and instances nest more than {MAX_NESTING} deep"),
            ));
        }
        st.visiting.push(name.to_string());
        let mut prototype = Prototype::default();
        // A shape's prototype holds it in its own space: the instance's transform replaces the
        // shape's `transform`.
        match def {
            Def::Group(g) => {
                let contents = Contents::group(g.get_ref(), key.clone());
                self.fill(st, names, &contents, &mut prototype, None)?;
            }
            Def::Sphere(s) => self.sphere(s, &key, names, true, &mut prototype)?,
            Def::Quadric(q) => {
                let mut local = q.clone();
                local.get_mut().transform = None;
                prototype.quadrics.push(self.quadric(&local, &key, names)?);
            }
            Def::Mesh(m) => {
                let mut local = m.clone();
                local.get_mut().transform = None;
                self.mesh_into(st, names, &local, &key, &mut prototype, None)?;
            }
        }
        st.visiting.pop();
        // Files' own prototypes (a glTF mesh placed by nodes) come without depths: 1 is a
        // lower bound that keeps the check meaningful for the scene's own groups.
        let depth = prototype
            .instances
            .iter()
            .map(|i| st.depths.get(i.prototype as usize).map_or(1, |d| d + 1))
            .max()
            .unwrap_or(0);
        // The world's instance of this prototype adds one more.
        if depth + 1 > MAX_NESTING {
            return Err(self.err(
                span,
                key,
                format!(
                    "groups and instances nest more than {MAX_NESTING} deep (\"{name}\" holds {depth} levels)"
                ),
            ));
        }
        // Every level's boxes are held in its own frame, whatever scale its instances place it
        // at, so a definition whose own contents pass the limit (its nested groups' transforms
        // multiply) is its error. Checked here, level by level, no box past the limit reaches
        // the next, and no product of transforms overflows to infinity. (Its box, found here,
        // is kept for the reach of what places it.)
        if let Some(reach) = st.prototype_boxes.admit(&st.prototypes, &prototype) {
            let at = match def {
                Def::Group(g) => g.span(),
                Def::Sphere(s) => s.span(),
                Def::Quadric(q) => q.span(),
                Def::Mesh(m) => m.span(),
            };
            return Err(self.err(
                at,
                key,
                format!(
                    "its contents reach coordinates up to {:e} in its own frame, before any \
                     instance places it; quadray supports magnitudes up to {:e}",
                    reach.far,
                    quadray::MAX_COORDINATE
                ),
            ));
        }
        let index = st.prototypes.len() as u32;
        st.depths.resize(st.prototypes.len(), 1);
        st.depths.push(depth);
        st.prototypes.push(prototype);
        st.built.insert(name.to_string(), index);
        Ok(index)
    }

    /// A `[[mesh]]`, inline or read from a file, into `out`; an imported file's planes go to
    /// `planes` (an error inside a group) and its prototypes to the scene's.
    fn mesh_into(
        &self,
        st: &mut GraphState<'_>,
        names: &HashMap<String, u32>,
        m: &Spanned<MeshSpec>,
        key: &str,
        out: &mut Prototype,
        planes: Option<&mut Vec<Plane>>,
    ) -> Result<(), LoadError> {
        if m.get_ref().path.is_none() {
            out.meshes.push(self.mesh(m, key, names)?);
            return Ok(());
        }
        let (imported, (path, replace)) = self.mesh_file(m, key, names)?;
        // Merged into a scratch geometry that holds the scene's prototypes, so the file's
        // prototypes are numbered after them.
        let mut scratch = Geometry {
            prototypes: std::mem::take(&mut st.prototypes),
            ..Geometry::default()
        };
        let merged = include::merge(
            imported,
            &path,
            replace,
            &mut st.materials,
            &mut st.material_names,
            &mut scratch,
        )
        .map_err(|e| self.include_err(m.get_ref().path.as_ref(), key, e))?;
        st.prototypes = std::mem::take(&mut scratch.prototypes);
        st.notes.extend(merged.notes);
        if !merged.lights.is_empty() || !merged.cameras.is_empty() {
            st.notes.push(format!(
                "{key}: the file's {} light(s) and {} camera(s) are not used by [[mesh]]; [[include]] brings them in",
                merged.lights.len(),
                merged.cameras.len()
            ));
        }
        match planes {
            Some(planes) => planes.append(&mut scratch.planes),
            None if !scratch.planes.is_empty() => {
                return Err(self.err(
                    m.span(),
                    key,
                    "the file holds an infinite plane, which cannot be in a group or instanced",
                ));
            }
            None => {}
        }
        out.spheres.append(&mut scratch.spheres);
        out.quadrics.append(&mut scratch.quadrics);
        out.meshes.append(&mut scratch.meshes);
        out.instances.append(&mut scratch.instances);
        Ok(())
    }
}
