//! `TrimCurve` and `Attribute "trimcurve" "sense"`: the trim state that the `NuPatch`
//! surfaces after it take ([`crate::scene::trim`] reads and flattens the loops).

use super::lexer::shown;
use super::state::Interp;
use super::syntax::{Arg, Args, Param, Request};
use crate::scene::SceneError;
use crate::scene::trim::{PatchTrim, TrimCurveArgs, trim_loops};
use std::sync::Arc;

impl Interp {
    /// `TrimCurve ncurves order knot min max n u v w`: sets the current trim loops (an
    /// attribute, saved by `AttributeBegin`); no loops turns trimming off.
    pub(super) fn trim_curve(&mut self, a: &mut Args) -> Result<(), SceneError> {
        let ncurves = a.array("ncurves")?;
        let order = a.array("order")?;
        let knot = a.array("knot")?;
        let min = a.array("min")?;
        let max = a.array("max")?;
        let n = a.array("n")?;
        let u = a.array("u")?;
        let v = a.array("v")?;
        let w = a.array("w")?;
        a.done()?;
        let loops = trim_loops(&TrimCurveArgs {
            ncurves,
            order,
            knot,
            min,
            max,
            n,
            u,
            v,
            w,
        })
        .map_err(|m| a.err(m))?;
        self.attrs.trim = loops.map(Arc::new);
        Ok(())
    }

    /// `Attribute "trimcurve" "sense" "inside"|"outside"`: which side of the loops is kept.
    pub(super) fn trim_attribute(
        &mut self,
        req: &Request,
        a: &Args,
        params: &[Param],
    ) -> Result<(), SceneError> {
        for p in params {
            if p.name != "sense" {
                self.ignored_param(req, p.name);
                continue;
            }
            let s = match p.value {
                Arg::Str(s) => Some(s.as_str()),
                Arg::Strs(v) if v.len() == 1 => Some(v[0].as_str()),
                _ => None,
            };
            self.attrs.trim_outside = match s {
                Some("inside") => false,
                Some("outside") => true,
                _ => {
                    return Err(a.err(format!(
                        "trimcurve \"sense\" {}: expected \"inside\" or \"outside\"",
                        s.map_or_else(|| p.value.describe(), |s| format!("\"{}\"", shown(s)))
                    )));
                }
            };
        }
        Ok(())
    }

    /// The trimming of each patch a `NuPatch` makes, in its order, from its (u, v) spans
    /// (`crate::scene::nurbs::patch_spans`); empty when untrimmed.
    pub(super) fn patch_trims(&self, spans: &[[(usize, f64, f64); 2]]) -> Vec<Arc<PatchTrim>> {
        let Some(loops) = &self.attrs.trim else {
            return Vec::new();
        };
        spans
            .iter()
            .map(|[u, v]| {
                Arc::new(PatchTrim {
                    loops: loops.clone(),
                    outside: self.attrs.trim_outside,
                    u: (u.1, u.2),
                    v: (v.1, v.2),
                })
            })
            .collect()
    }
}
