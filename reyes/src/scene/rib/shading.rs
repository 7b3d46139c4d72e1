//! Shading requests: `Surface` and `LightSource`, and the table of distinct materials the
//! patches index.

use super::lexer::shown;
use super::state::Interp;
use super::syntax::{Arg, Args, Request};
use crate::scene::{Light, Material, SceneError, SurfaceKind};
use glam::DVec3;

/// The surface shaders `Surface` knows (a misspelt one's warning suggests the closest).
const SURFACE_NAMES: &[&str] = &[
    "constant",
    "matte",
    "plastic",
    "metal",
    "shinymetal",
    "paintedplastic",
];

impl Interp {
    pub(super) fn surface(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let name = a.string("the shader name")?;
        let kind = match name {
            "constant" => SurfaceKind::Constant,
            "matte" => SurfaceKind::Matte,
            "plastic" => SurfaceKind::Plastic,
            "metal" => SurfaceKind::Metal,
            // RenderMan's textured variants: without a texture (`texturename` "", the default)
            // they are exactly metal and plastic; a texture is ignored with a warning.
            "shinymetal" => SurfaceKind::Metal,
            "paintedplastic" => SurfaceKind::Plastic,
            _ => {
                let msg = super::requests::with_suggestion(
                    format!(
                        "skipped unsupported surface shader \"{}\" (keeping the previous surface)",
                        shown(name)
                    ),
                    name,
                    SURFACE_NAMES,
                );
                self.warn_once(req, &format!("Surface \"{name}\""), &msg);
                return Ok(());
            }
        };
        let mut m = Material::standard(kind);
        for p in a.params()? {
            match (kind, p.name) {
                (SurfaceKind::Matte | SurfaceKind::Plastic | SurfaceKind::Metal, "Ka") => {
                    m.ka = p.num(a)?
                }
                (SurfaceKind::Matte | SurfaceKind::Plastic, "Kd") => m.kd = p.num(a)?,
                (SurfaceKind::Plastic | SurfaceKind::Metal, "Ks") => m.ks = p.num(a)?,
                (SurfaceKind::Plastic | SurfaceKind::Metal, "roughness") => {
                    m.roughness = p.num(a)?
                }
                (SurfaceKind::Plastic, "specularcolor") => m.specular_color = p.vec3(a)?,
                (_, other) => self.ignored_param(req, other),
            }
        }
        let values = [m.ka, m.kd, m.ks, m.roughness];
        if values.iter().any(|v| !(*v as f32).is_finite())
            || !m.specular_color.as_vec3().is_finite()
        {
            return Err(a.err("a shader parameter is beyond the f32 range the renderer shades in"));
        }
        self.attrs.surface = m;
        self.current_material = None;
        Ok(())
    }

    pub(super) fn light(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let name = a.string("the shader name")?;
        // The handle: a number, or (RIB 3.04) a string followed by an even-length list.
        match a.peek() {
            Some(Arg::Num(_)) => {
                a.pos += 1;
            }
            Some(Arg::Str(_)) if (req.args.len() - a.pos) % 2 == 1 => {
                a.pos += 1;
            }
            _ => {}
        }
        let params = a.params()?;
        if !matches!(name, "ambientlight" | "distantlight" | "pointlight") {
            let msg = format!(
                "skipped unsupported light shader \"{}\" (no light added)",
                shown(name)
            );
            self.warn_once(req, &format!("LightSource \"{name}\""), &msg);
            return Ok(());
        }
        let mut intensity = 1.0;
        let mut color = DVec3::ONE;
        let mut from = DVec3::ZERO;
        let mut to = DVec3::Z;
        for p in &params {
            match (name, p.name) {
                (_, "intensity") => intensity = p.num(a)?,
                (_, "lightcolor") => color = p.vec3(a)?,
                ("distantlight" | "pointlight", "from") => from = p.vec3(a)?,
                ("distantlight", "to") => to = p.vec3(a)?,
                (_, other) => self.ignored_param(req, other),
            }
        }
        let color = color * intensity;
        let ctm = self.attrs.ctm;
        let light = match name {
            "ambientlight" => Light::Ambient { color },
            "distantlight" => {
                let d = ctm.project_point3(to) - ctm.project_point3(from);
                let dir = d.normalize_or_zero();
                if dir == DVec3::ZERO || !dir.is_finite() {
                    return Err(a.err("\"from\" and \"to\" give no direction"));
                }
                Light::Distant { color, dir }
            }
            _ => {
                let pos = ctm.project_point3(from);
                if !pos.is_finite() {
                    return Err(a.err("the light position is not finite"));
                }
                Light::Point { color, pos }
            }
        };
        let (Light::Ambient { color } | Light::Distant { color, .. } | Light::Point { color, .. }) =
            &light;
        let pos = match &light {
            Light::Point { pos, .. } => *pos,
            _ => DVec3::ZERO,
        };
        if [*color, pos].iter().any(|v| !v.as_vec3().is_finite()) {
            return Err(a.err(
                "the light's color or position is beyond the f32 range the renderer computes in",
            ));
        }
        self.scene.lights.push(light);
        Ok(())
    }

    pub(super) fn material(&mut self) -> u32 {
        if let Some(m) = self.current_material {
            return m;
        }
        let m = Material {
            color: self.attrs.color,
            opacity: self.attrs.opacity,
            ..self.attrs.surface.clone()
        };
        let key = (
            m.kind,
            [
                m.color.x,
                m.color.y,
                m.color.z,
                m.opacity.x,
                m.opacity.y,
                m.opacity.z,
                m.ka,
                m.kd,
                m.ks,
                m.roughness,
                m.specular_color.x,
                m.specular_color.y,
                m.specular_color.z,
            ]
            .map(f64::to_bits),
        );
        let next = self.scene.materials.len() as u32;
        let id = *self.materials.entry(key).or_insert(next);
        if id == next {
            self.scene.materials.push(m);
        }
        self.current_material = Some(id);
        id
    }
}
