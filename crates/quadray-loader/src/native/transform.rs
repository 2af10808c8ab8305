//! `transform` tables: scale, rotate (Euler angles or a quaternion) and translate, or a full
//! affine matrix.

use super::*;
use glam::{DAffine3, DMat3, DQuat};

impl Builder<'_> {
    /// The transform an imported file is placed by (an `[[include]]`'s or a `[[mesh]]`'s):
    /// `None` where the file gives none, so the import checks what the file itself places (an
    /// OBJ vertex at its line, a glTF node by its index).
    pub(super) fn import_transform(
        &self,
        spec: &Option<Spanned<TransformSpec>>,
        key: &str,
    ) -> Result<Option<Transform>, LoadError> {
        match spec {
            Some(_) => Ok(Some(self.transform(spec, key)?)),
            None => Ok(None),
        }
    }

    /// The object-to-parent map a `transform` table describes (the identity when absent).
    pub(super) fn transform(
        &self,
        spec: &Option<Spanned<TransformSpec>>,
        key: &str,
    ) -> Result<Transform, LoadError> {
        let Some(spec) = spec else {
            return Ok(Transform::IDENTITY);
        };
        let t = spec.get_ref();
        if let Some(m) = &t.matrix {
            let others = [
                (t.translate.is_some(), "translate"),
                (t.rotate.is_some(), "rotate"),
                (t.rotation.is_some(), "rotation"),
                (t.scale.is_some(), "scale"),
            ];
            if let Some((_, other)) = others.iter().find(|(present, _)| *present) {
                return Err(self.err(
                    spec.span(),
                    format!("{key}.{other}"),
                    "a transform is either a `matrix` or translate/rotate/scale, not both",
                ));
            }
            return self.matrix(m, &format!("{key}.matrix"));
        }
        if let (Some(_), Some(q)) = (&t.rotate, &t.rotation) {
            return Err(self.err(
                q.span(),
                format!("{key}.rotation"),
                "give either `rotate` (Euler angles) or `rotation` (a quaternion), not both",
            ));
        }
        let translate = t
            .translate
            .as_ref()
            .map(|v| self.vec3(v, &format!("{key}.translate")))
            .transpose()?
            .unwrap_or_default();
        let scale = match &t.scale {
            None => DVec3::ONE,
            Some(s) => {
                let v = match s.get_ref() {
                    ScaleSpec::Uniform(k) => DVec3::splat(*k),
                    ScaleSpec::PerAxis(v) => DVec3::from_array(v.0),
                };
                if !(v.is_finite() && v.cmpne(DVec3::ZERO).all()) {
                    return Err(self.err(
                        s.span(),
                        format!("{key}.scale"),
                        format!("must be finite and nonzero, got {v}"),
                    ));
                }
                v
            }
        };
        let singular = || self.err(spec.span(), key, "the transform is singular");
        if let Some(q) = &t.rotation {
            let rotation = self.quaternion(q, &format!("{key}.rotation"))?;
            return Transform::new(DAffine3::from_scale_rotation_translation(
                scale, rotation, translate,
            ))
            .ok_or_else(singular);
        }
        let rotate = t
            .rotate
            .as_ref()
            .map(|v| self.vec3(v, &format!("{key}.rotate")))
            .transpose()?;
        Transform::from_srt(scale, rotate.unwrap_or_default(), translate).ok_or_else(singular)
    }

    /// A unit quaternion from [x, y, z, w]; other lengths are normalised, zero is an error.
    fn quaternion(
        &self,
        q: &Spanned<super::exact::Exact<f64, 4>>,
        key: &str,
    ) -> Result<DQuat, LoadError> {
        let [x, y, z, w] = q.get_ref().0;
        let quat = DQuat::from_xyzw(x, y, z, w);
        let length = quat.length();
        if !(quat.is_finite() && length > 0.0 && length.is_finite()) {
            return Err(self.err(
                q.span(),
                key,
                format!(
                    "must be a finite, nonzero quaternion [x, y, z, w], got {q:?}",
                    q = q.get_ref().0
                ),
            ));
        }
        Ok(quat / length)
    }

    /// A 4x4 row-major matrix that must be affine (last row 0 0 0 1), finite and invertible.
    fn matrix(
        &self,
        m: &Spanned<super::exact::Exact<super::exact::Exact<f64, 4>, 4>>,
        key: &str,
    ) -> Result<Transform, LoadError> {
        let rows = m.get_ref().0.map(|row| row.0);
        if rows.iter().flatten().any(|v| !v.is_finite()) {
            return Err(self.err(
                m.span(),
                key,
                "must be finite numbers (found NaN or infinity)",
            ));
        }
        self.within_limit(rows.iter().flatten().copied(), m.span(), key)?;
        if rows[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(self.err(
                m.span(),
                key,
                format!(
                    "must be affine: the last row must be [0, 0, 0, 1], got {:?} (projective maps are not supported)",
                    rows[3]
                ),
            ));
        }
        let linear = DMat3::from_cols_array_2d(&[
            [rows[0][0], rows[1][0], rows[2][0]],
            [rows[0][1], rows[1][1], rows[2][1]],
            [rows[0][2], rows[1][2], rows[2][2]],
        ]);
        let translation = DVec3::new(rows[0][3], rows[1][3], rows[2][3]);
        Transform::new(DAffine3::from_mat3_translation(linear, translation)).ok_or_else(|| {
            self.err(
                m.span(),
                key,
                format!(
                    "is singular (determinant {:e}): it flattens space and cannot be inverted",
                    linear.determinant()
                ),
            )
        })
    }
}
