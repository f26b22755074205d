//! The material table: friction and restitution per pair of material names.

/// Friction and restitution of a pair of materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Coulomb friction μ ≥ 0.
    pub friction: f64,
    /// Restitution e ∈ [0, 1] (Stronge's energetic coefficient).
    pub restitution: f64,
}

impl Material {
    /// Checks μ ≥ 0 and e ∈ [0, 1], both finite.
    ///
    /// # Errors
    /// A sentence naming the value that is out of range.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(format!("friction {} must be finite and ≥ 0", self.friction));
        }
        if !(self.restitution.is_finite() && (0.0..=1.0).contains(&self.restitution)) {
            return Err(format!(
                "restitution {} must lie in [0, 1]",
                self.restitution
            ));
        }
        Ok(())
    }
}

/// Material names and the contact of every pair of them (`default` first).
#[derive(Clone, Debug)]
pub(crate) struct Materials {
    names: Vec<String>,
    /// `[a * n + b]`, symmetric.
    table: Vec<Material>,
    default: Material,
}

impl Materials {
    pub(crate) fn new(default: Material) -> Self {
        Self {
            names: vec!["default".into()],
            table: vec![default],
            default,
        }
    }

    /// The index of material `name`, added (with the default contact against every other)
    /// when new.
    pub(crate) fn index(&mut self, name: &str) -> usize {
        if let Some(i) = self.names.iter().position(|m| m == name) {
            return i;
        }
        let n = self.names.len();
        let mut table = vec![self.default; (n + 1) * (n + 1)];
        for a in 0..n {
            for b in 0..n {
                table[a * (n + 1) + b] = self.table[a * n + b];
            }
        }
        self.names.push(name.to_string());
        self.table = table;
        n
    }

    /// Sets the contact of materials `a` and `b` (either order).
    pub(crate) fn set(&mut self, a: &str, b: &str, m: Material) {
        let (i, j) = (self.index(a), self.index(b));
        let n = self.names.len();
        self.table[i * n + j] = m;
        self.table[j * n + i] = m;
    }

    /// The contact of materials with indices `i` and `j`.
    pub(crate) fn get(&self, i: usize, j: usize) -> Material {
        self.table[i * self.names.len() + j]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_are_symmetric_and_new_names_get_the_default() {
        let d = Material {
            friction: 0.3,
            restitution: 0.5,
        };
        let steel = Material {
            friction: 0.2,
            restitution: 0.9,
        };
        let mut m = Materials::new(d);
        m.set("steel", "default", steel);
        let wood = m.index("wood");
        let s = m.index("steel");
        assert_eq!(m.get(s, 0), steel);
        assert_eq!(m.get(0, s), steel);
        assert_eq!(m.get(wood, s), d);
        assert_eq!(m.get(s, s), d);
        assert_eq!(m.index("steel"), s);
    }
}
