//! `[camera]` and `[output]`: how the scene is seen and where its image goes.

use super::*;

impl Builder<'_> {
    pub(super) fn camera(&self, spec: &Spanned<CameraSpec>) -> Result<Camera, LoadError> {
        let c = spec.get_ref();
        let vfov = c
            .vfov
            .as_ref()
            .map(|v| self.number(v, "camera.vfov"))
            .transpose()?
            .unwrap_or(40.0);
        let up =
            c.up.as_ref()
                .map(|v| self.vec3(v, "camera.up"))
                .transpose()?
                .unwrap_or(DVec3::Z);
        let projection = c
            .projection
            .as_ref()
            .map(|p| (p.get_ref().as_str(), p.span()));
        let camera = match (&c.orbit, projection) {
            (Some(orbit), None | Some(("perspective", _))) => {
                if c.from.is_some() || c.to.is_some() {
                    return Err(self.err(
                        spec.span(),
                        "camera",
                        "give either `orbit` or `from`/`to`, not both",
                    ));
                }
                let o = orbit.get_ref();
                let target = o
                    .target
                    .as_ref()
                    .map(|v| self.vec3(v, "camera.orbit.target"))
                    .transpose()?
                    .unwrap_or_default();
                let distance = self.positive(&o.distance, "camera.orbit.distance")?;
                let yaw = self.number(&o.yaw, "camera.orbit.yaw")?;
                let pitch = self.number(&o.pitch, "camera.orbit.pitch")?;
                if !(-90.0..=90.0).contains(&pitch) {
                    return Err(self.err(
                        o.pitch.span(),
                        "camera.orbit.pitch",
                        format!("must be within [-90, 90] degrees (an elevation), got {pitch}"),
                    ));
                }
                Camera::orbit(target, yaw, pitch, distance, vfov)
            }
            (Some(orbit), Some(_)) => {
                return Err(self.err(
                    orbit.span(),
                    "camera.orbit",
                    "an orbit camera is perspective",
                ));
            }
            (None, projection) => {
                let from = c.from.as_ref().ok_or_else(|| {
                    self.err(spec.span(), "camera", "needs `from` and `to`, or `orbit`")
                })?;
                let to =
                    c.to.as_ref()
                        .ok_or_else(|| self.err(spec.span(), "camera", "needs `to`"))?;
                let projection = match projection {
                    None | Some(("perspective", _)) => Projection::Perspective { vfov_deg: vfov },
                    Some(("orthographic", span)) => {
                        let h = c.height.as_ref().ok_or_else(|| {
                            self.err(
                                span,
                                "camera.height",
                                "an orthographic camera needs `height`",
                            )
                        })?;
                        Projection::Orthographic {
                            height: self.positive(h, "camera.height")?,
                        }
                    }
                    Some((other, span)) => {
                        return Err(self.err(
                            span,
                            "camera.projection",
                            format!(
                                "unknown projection \"{other}\" (perspective, orthographic){}",
                                did_you_mean(other, ["perspective", "orthographic"])
                            ),
                        ));
                    }
                };
                Camera {
                    from: self.vec3(from, "camera.from")?,
                    to: self.vec3(to, "camera.to")?,
                    up,
                    projection,
                }
            }
        };
        camera
            .prepare(1.0)
            .map_err(|e| self.err(spec.span(), "camera", e.to_string()))?;
        Ok(camera)
    }

    /// The `[output]` file, resolved against the scene file's folder; it must name a PNG or EXR.
    pub(super) fn output(&self, o: &OutputSpec) -> Result<PathBuf, LoadError> {
        let written = o.file.get_ref();
        let is_image = Path::new(written)
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr"));
        if !is_image || written.trim().is_empty() {
            return Err(self.err(
                o.file.span(),
                "output.file",
                format!("must name a .png or .exr file, got \"{written}\""),
            ));
        }
        let folder = self.path.parent().unwrap_or(Path::new(""));
        Ok(folder.join(written))
    }
}

/// Notes for `[camera]` keys its projection does not use: `height` on a perspective camera (an
/// orbit camera is one), `vfov` on an orthographic one. Notes rather than errors, so that
/// `--set camera.projection="orthographic" --set camera.height=4` works on a file that gives a
/// `vfov`.
pub(super) fn unused_camera_keys(c: &CameraSpec) -> Vec<String> {
    let orthographic = c
        .projection
        .as_ref()
        .is_some_and(|p| p.get_ref() == "orthographic");
    let mut notes = Vec::new();
    if orthographic && c.vfov.is_some() {
        notes.push(
            "camera.vfov is not used: an orthographic camera's view is its `height`".to_string(),
        );
    }
    if !orthographic && c.height.is_some() {
        notes.push(
            "camera.height is not used: a perspective camera's view is its `vfov` (`height` is \
             an orthographic camera's)"
                .to_string(),
        );
    }
    notes
}
