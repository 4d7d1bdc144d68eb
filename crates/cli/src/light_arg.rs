//! `--light`: point, spot and directional lights added to a scene from the command line.

use spectral::spectrum::Colour;
use tracer::PunctualLight;

/// The syntax, for `--help` and error messages.
pub(crate) const LIGHT_SYNTAX: &str = "point:X,Y,Z:I | spot:X,Y,Z:DX,DY,DZ:INNER,OUTER:I | sun:DX,DY,DZ:E[:DIAMETER] \
     (I, E: one value for white or R,G,B in linear sRGB; INNER, OUTER: cone half-angles in degrees; \
     D: the direction the light shines in; DIAMETER: the sun disk's angular diameter in degrees, \
     0 (a delta direction) by default, 0.53 for the real sun)";

/// Parses one `--light` value.
pub(crate) fn parse_light(s: &str) -> Result<PunctualLight, String> {
    let fields: Vec<&str> = s.split(':').collect();
    let bad = |why: String| format!("--light '{s}': {why} (expected {LIGHT_SYNTAX})");
    let vec3 = |f: &str, what: &str| crate::parse_vec3(f).map_err(|e| bad(format!("{what}: {e}")));
    let colour = |f: &str| parse_colour(f).map_err(&bad);
    let direction = |f: &str| {
        let d = vec3(f, "direction")?;
        if d.length_squared() > 0.0 { Ok(d) } else { Err(bad("the direction is zero".into())) }
    };
    let light = match fields.as_slice() {
        ["point", p, i] => PunctualLight::point(vec3(p, "position")?, colour(i)?),
        ["spot", p, d, cones, i] => {
            let angles: Vec<f32> = cones
                .split(',')
                .map(|a| a.trim().parse::<f32>().map_err(|_| bad(format!("'{a}' is not an angle"))))
                .collect::<Result<_, _>>()?;
            let [inner, outer] = angles[..] else {
                return Err(bad(format!("'{cones}': expected INNER,OUTER in degrees")));
            };
            if !(0.0..=180.0).contains(&inner) || !(inner..=180.0).contains(&outer) {
                return Err(bad(format!("cone angles {inner}°, {outer}°: need 0 ≤ INNER ≤ OUTER ≤ 180")));
            }
            PunctualLight::spot(vec3(p, "position")?, direction(d)?, colour(i)?, inner.to_radians(), outer.to_radians())
        }
        ["sun" | "directional", d, e] => PunctualLight::directional(direction(d)?, colour(e)?),
        ["sun" | "directional", d, e, diameter] => {
            let deg: f32 = diameter.trim().parse().map_err(|_| bad(format!("'{diameter}' is not an angle")))?;
            if !(0.0..90.0).contains(&deg) {
                return Err(bad(format!("sun diameter {deg}°: need 0 ≤ DIAMETER < 90")));
            }
            PunctualLight::sun(direction(d)?, colour(e)?, deg.to_radians())
        }
        [kind, ..] if !matches!(*kind, "point" | "spot" | "sun" | "directional") => {
            return Err(bad(format!("unknown light kind '{kind}'")));
        }
        _ => return Err(bad("wrong number of ':'-separated fields".into())),
    };
    light.validate().map_err(bad)?;
    Ok(light)
}

/// One value v (white: linear sRGB (v, v, v)) or R,G,B; an illuminant uplifted as the
/// scene files' emission colours are.
fn parse_colour(s: &str) -> Result<Colour, String> {
    let values: Vec<f32> = s
        .split(',')
        .map(|v| v.trim().parse::<f32>().map_err(|_| format!("'{v}' is not a number")))
        .collect::<Result<_, _>>()?;
    let rgb = match values[..] {
        [v] => [v; 3],
        [r, g, b] => [r, g, b],
        _ => return Err(format!("'{s}': expected one value or R,G,B")),
    };
    if rgb.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
        return Err(format!("'{s}': the colour must be finite and non-negative"));
    }
    Colour::illuminant_rgb(rgb).map_err(|e| format!("'{s}': {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn lights_parse_and_bad_ones_say_why() {
        let point = parse_light("point:0,2,0:3").unwrap();
        assert_eq!(point.kind(), "point");
        assert!((point.colour().rgb[0] - 3.0).abs() < 1e-2);
        let spot = parse_light("spot:0,2,0:0,-1,0:20,30:1,2,3").unwrap();
        let PunctualLight::Spot { direction, cos_inner, cos_outer, .. } = spot else { panic!("{spot:?}") };
        assert_eq!(direction, -Vec3::Y);
        assert!((cos_inner - 20f32.to_radians().cos()).abs() < 1e-6);
        assert!((cos_outer - 30f32.to_radians().cos()).abs() < 1e-6);
        let sun = parse_light("sun:1,-1,0:2").unwrap();
        let PunctualLight::Directional { direction, .. } = sun else { panic!("{sun:?}") };
        assert!((direction - Vec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-6);
        assert!(sun.disk().is_none());
        let disk = parse_light("sun:0,-1,0:2:0.53").unwrap();
        let (axis, cos_radius, _) = disk.disk().expect("a sun disk");
        assert_eq!((axis, disk.kind()), (Vec3::Y, "sun disk"));
        assert!((cos_radius - 0.265f32.to_radians().cos()).abs() < 1e-7);
        for (bad, says) in [
            ("sun:0,-1,0:2:95", "need 0 ≤ DIAMETER < 90"),
            ("sun:0,-1,0:2:wide", "'wide' is not an angle"),
            ("lamp:0,0,0:1", "unknown light kind 'lamp'"),
            ("point:0,0:1", "position"),
            ("point:0,0,0:-1", "non-negative"),
            ("point:0,0,0:1,2", "one value or R,G,B"),
            ("point:0,0,0", "number of"),
            ("sun:0,0,0:1", "direction is zero"),
            ("spot:0,0,0:0,-1,0:30,20:1", "INNER ≤ OUTER"),
            ("spot:0,0,0:0,-1,0:30:1", "INNER,OUTER"),
            ("point:nan,0,0:1", "position"),
        ] {
            let e = parse_light(bad).unwrap_err();
            assert!(e.contains(says) && e.contains(bad), "{bad}: {e}");
        }
    }
}
