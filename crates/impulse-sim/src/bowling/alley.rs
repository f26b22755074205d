//! The bowling alley of a study: lane, gutters, pit, optional kickbacks, ten pins and the
//! ball, as numbers ([`AlleyDesc`], a RON file) and as a scene ([`AlleyDesc::scene`]).
//!
//! The thesis gives no numbers ("accurate physical dimensions and masses … except for a
//! slight approximation in the shape of the pins", §7.4); the defaults are the USBC
//! specification's, in metres, as listed in each field's documentation. They are not from
//! the thesis, and the pin's lathe profile is our own reading of the specification's table.

use serde::{Deserialize, Serialize};

use crate::SimError;
use crate::scene::{BodyDesc, ContactDesc, PartDesc, SceneDesc, ShapeDesc};
use crate::world::Material;

/// Inches to metres.
const INCH: f64 = 0.0254;

/// Depth of the pit floor below the lane surface (m). Default `0.3`.
pub const PIT_DEPTH: f64 = 0.3;

/// Length of the pit floor beyond the deck, to its back wall (m). Default `1.5`.
pub const PIT_LENGTH: f64 = 1.5;

/// The lane begins this far behind the foul line (m; the ball starts on the foul line).
pub const APPROACH: f64 = 1.0;

/// Thickness of the fixed boxes that make the lane, gutters, pit and kickbacks (m).
pub const SLAB: f64 = 0.05;

/// Flat facets a gutter's circular cross-section is drawn with (odd: one at the bottom).
/// Default `7`.
pub const GUTTER_FACETS: u32 = 7;

/// Height of the gutters' outer walls above the lane (m). Default `0.1`.
pub const GUTTER_WALL_HEIGHT: f64 = 0.1;

/// Height of a kickback, and of the pit's back wall, above the lane (m). Default `0.6`.
pub const KICKBACK_HEIGHT: f64 = 0.6;

/// How far in front of the head pin the kickbacks begin (m). Default `0.3`.
pub const KICKBACK_LEAD: f64 = 0.3;

/// A pin or the ball is placed this fraction of ε_c above the lane: touching, not
/// overlapping.
pub const PLACE_GAP_REL: f64 = 0.01;

/// The pins' names in the scene: `pin1` … `pin10`, numbered as bowlers do (1 the head pin;
/// 2, 3 the second row left to right; 4–6; 7–10).
pub const PIN_COUNT: usize = 10;

/// The ten-pin triangle: (row, position across the row in pin spacings), by pin number − 1.
/// Row r stands r·spacing·cos 30° beyond the head pin; x grows to the bowler's right.
const RACK: [(f64, f64); PIN_COUNT] = [
    (0.0, 0.0),
    (1.0, -0.5),
    (1.0, 0.5),
    (2.0, -1.0),
    (2.0, 0.0),
    (2.0, 1.0),
    (3.0, -1.5),
    (3.0, -0.5),
    (3.0, 0.5),
    (3.0, 1.5),
];

/// Most sides of a pin's polygonal cross-section.
pub const MAX_PIN_SIDES: u32 = 256;

/// A pin: a solid of revolution about its own z axis, base at z = 0, as stacked frusta
/// (convex pieces of one compound body) over a regular polygon.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Pin", deny_unknown_fields)]
pub struct PinDesc {
    /// The lathe profile: (height above the base, diameter) (m), heights increasing; each
    /// pair of neighbours is one frustum. Default: the USBC table at 0, ¾, 2¼, 4½, 7¼, 10,
    /// 11¾, 13½, 14.6 and 15 in (base 2.03 in, belly 4.766 in at 4½ in, neck 1.8 in at
    /// 10 in, head 2.54 in at 13½ in).
    pub profile: Vec<[f64; 2]>,
    /// Sides of the polygon the profile's circles are drawn as (inscribed). Default `12`.
    pub sides: u32,
    /// Mass (kg), spread uniformly. Default `1.55` (USBC: 3 lb 6 oz to 3 lb 10 oz).
    pub mass: f64,
    /// Distance between neighbouring pins' centres (m). Default 12 in.
    pub spacing: f64,
}

/// The ball: a solid sphere of uniform density.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Ball", deny_unknown_fields)]
pub struct BallDesc {
    /// Radius (m). Default `0.108` (8.5 in diameter, the USBC minimum is 8.5 in).
    pub radius: f64,
    /// Mass (kg). Default `7.26` (16 lb, the USBC maximum).
    pub mass: f64,
}

/// Friction and restitution of each pair of the alley's materials (`lane` is the lane,
/// gutters, pit and kickbacks). The thesis gives none; the defaults are typical values,
/// stated as assumptions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Contacts", deny_unknown_fields)]
pub struct AlleyContacts {
    /// Ball on lane. Default μ 0.2 (a dry back end), e 0.3.
    pub ball_lane: ContactDesc,
    /// Ball on pin. Default μ 0.15, e 0.65.
    pub ball_pin: ContactDesc,
    /// Pin on pin. Default μ 0.15, e 0.6.
    pub pin_pin: ContactDesc,
    /// Pin on lane. Default μ 0.2, e 0.4.
    pub pin_lane: ContactDesc,
}

/// A bowling alley: the numbers a study's scenes are built from (a RON file, `Alley(…)`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Alley", deny_unknown_fields)]
pub struct AlleyDesc {
    /// Lane width between the gutters (m). Default 41.5 in.
    pub lane_width: f64,
    /// Foul line to the head pin's centre (m). Default 60 ft.
    pub head_pin_distance: f64,
    /// Head pin's centre to the pit edge, the deck's end (m). Default 34 3/16 in.
    pub deck_beyond_head_pin: f64,
    /// Width of each gutter (m). Default 9.25 in.
    pub gutter_width: f64,
    /// Depth of a gutter below the lane (m), at the middle of its circular cross-section.
    /// Default 1 7/8 in.
    pub gutter_depth: f64,
    /// Whether kickbacks (side walls beside the pin deck) stand outside the gutters. Default
    /// `false` (the thesis does not mention them).
    pub kickbacks: bool,
    /// Collision epsilon ε_c (m). Default `1e-3` (thesis §2.2: "in the bowling simulation …
    /// ε_c was one millimeter").
    pub collision_epsilon: f64,
    /// The pins.
    pub pin: PinDesc,
    /// The ball.
    pub ball: BallDesc,
    /// Contact properties.
    pub contacts: AlleyContacts,
}

impl Default for AlleyDesc {
    fn default() -> Self {
        let profile = [
            (0.0, 2.03),
            (0.75, 3.0),
            (2.25, 4.4),
            (4.5, 4.766),
            (7.25, 3.8),
            (10.0, 1.8),
            (11.75, 2.0),
            (13.5, 2.54),
            (14.6, 2.0),
            (15.0, 0.9),
        ];
        Self {
            lane_width: 41.5 * INCH,
            head_pin_distance: 60.0 * 12.0 * INCH,
            deck_beyond_head_pin: (34.0 + 3.0 / 16.0) * INCH,
            gutter_width: 9.25 * INCH,
            gutter_depth: 1.875 * INCH,
            kickbacks: false,
            collision_epsilon: 1e-3,
            pin: PinDesc {
                profile: profile.map(|(h, d)| [h * INCH, d * INCH]).to_vec(),
                sides: 12,
                mass: 1.55,
                spacing: 12.0 * INCH,
            },
            ball: BallDesc {
                radius: 0.108,
                mass: 7.26,
            },
            contacts: AlleyContacts {
                ball_lane: ContactDesc::new(0.2, 0.3),
                ball_pin: ContactDesc::new(0.15, 0.65),
                pin_pin: ContactDesc::new(0.15, 0.6),
                pin_lane: ContactDesc::new(0.2, 0.4),
            },
        }
    }
}

impl AlleyDesc {
    /// Parses an alley file (RON). `source` names the text in errors.
    ///
    /// # Errors
    /// [`SimError::Parse`] with the position of the problem; [`SimError::Invalid`] naming a
    /// bad field.
    pub fn from_ron(text: &str, source: &str) -> Result<Self, SimError> {
        let desc: Self = ron::Options::default()
            .from_str(text)
            .map_err(|e| SimError::Parse {
                source_name: source.to_string(),
                message: e.to_string(),
            })?;
        desc.validate()?;
        Ok(desc)
    }

    /// The alley as RON text (what [`AlleyDesc::from_ron`] reads back equal).
    ///
    /// # Errors
    /// [`SimError::Parse`] if serialisation fails (it does not for finite numbers).
    pub fn to_ron(&self) -> Result<String, SimError> {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default().struct_names(true))
            .map_err(|e| SimError::Parse {
                source_name: "alley".into(),
                message: e.to_string(),
            })
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the field and the problem.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: "bowling alley".into(),
            field: field.into(),
            problem,
        };
        let positive = |field: &str, x: f64| crate::scene::positive(x).map_err(|p| bad(field, p));
        positive("lane_width", self.lane_width)?;
        positive("head_pin_distance", self.head_pin_distance)?;
        positive("deck_beyond_head_pin", self.deck_beyond_head_pin)?;
        positive("gutter_width", self.gutter_width)?;
        positive("gutter_depth", self.gutter_depth)?;
        if self.gutter_depth > self.gutter_width / 2.0 {
            return Err(bad(
                "gutter_depth",
                format!(
                    "{} is more than half the gutter's width {}: a circular gutter is at most a half circle",
                    self.gutter_depth, self.gutter_width
                ),
            ));
        }
        positive("collision_epsilon", self.collision_epsilon)?;
        positive("pin.mass", self.pin.mass)?;
        positive("pin.spacing", self.pin.spacing)?;
        positive("ball.radius", self.ball.radius)?;
        positive("ball.mass", self.ball.mass)?;
        if !(3..=MAX_PIN_SIDES).contains(&self.pin.sides) {
            return Err(bad(
                "pin.sides",
                format!("{} must be 3 to {MAX_PIN_SIDES}", self.pin.sides),
            ));
        }
        let p = &self.pin.profile;
        if p.len() < 2 {
            return Err(bad(
                "pin.profile",
                format!("{} points: need at least 2 (height, diameter)", p.len()),
            ));
        }
        for (k, &[h, d]) in p.iter().enumerate() {
            if !(h.is_finite() && d.is_finite() && h >= 0.0 && d >= 0.0) {
                return Err(bad(
                    "pin.profile",
                    format!("point {k} ({h}, {d}): height and diameter must be finite and ≥ 0"),
                ));
            }
        }
        if p[0][0] != 0.0 {
            return Err(bad(
                "pin.profile",
                format!("the first point's height is {}: the base is at 0", p[0][0]),
            ));
        }
        for (k, w) in p.windows(2).enumerate() {
            if w[1][0] <= w[0][0] {
                return Err(bad(
                    "pin.profile",
                    format!("point {}: heights must increase", k + 1),
                ));
            }
            if w[0][1] == 0.0 && w[1][1] == 0.0 {
                return Err(bad(
                    "pin.profile",
                    format!("points {k} and {}: a piece of zero diameter", k + 1),
                ));
            }
        }
        if p[0][1] == 0.0 {
            return Err(bad(
                "pin.profile",
                "the base's diameter is 0: the pin cannot stand".into(),
            ));
        }
        let widest = p.iter().map(|q| q[1]).fold(0.0, f64::max);
        if widest >= self.pin.spacing {
            return Err(bad(
                "pin.spacing",
                format!(
                    "{} is not more than the pin's widest diameter {widest}: the pins overlap",
                    self.pin.spacing
                ),
            ));
        }
        let rack_half_width = 1.5 * self.pin.spacing + widest / 2.0;
        if rack_half_width > self.lane_width / 2.0 {
            return Err(bad(
                "lane_width",
                format!(
                    "{}: the pins need {:.4} m",
                    self.lane_width,
                    2.0 * rack_half_width
                ),
            ));
        }
        let rack_depth = 3.0 * self.row_spacing() + p[0][1] / 2.0;
        if rack_depth > self.deck_beyond_head_pin {
            return Err(bad(
                "deck_beyond_head_pin",
                format!(
                    "{}: the last row's bases need {rack_depth:.4} m",
                    self.deck_beyond_head_pin
                ),
            ));
        }
        for (field, c) in [
            ("contacts.ball_lane", self.contacts.ball_lane),
            ("contacts.ball_pin", self.contacts.ball_pin),
            ("contacts.pin_pin", self.contacts.pin_pin),
            ("contacts.pin_lane", self.contacts.pin_lane),
        ] {
            Material {
                friction: c.friction,
                restitution: c.restitution,
            }
            .validate()
            .map_err(|e| bad(field, e))?;
        }
        Ok(())
    }

    /// Distance between rows of pins along the lane: spacing · cos 30°.
    pub fn row_spacing(&self) -> f64 {
        self.pin.spacing * 3f64.sqrt() / 2.0
    }

    /// The pin line's y (the head pin's centre; the foul line is y = 0, the lane runs along
    /// +y, x to the bowler's right, z up with the lane surface at 0).
    pub fn pin_line(&self) -> f64 {
        self.head_pin_distance
    }

    /// The deck's end, where the pit begins (y).
    pub fn deck_end(&self) -> f64 {
        self.head_pin_distance + self.deck_beyond_head_pin
    }

    /// Where pin `number` (1…10) stands: its base centre on the deck (x, y); `None` for
    /// another number.
    pub fn pin_spot(&self, number: usize) -> Option<[f64; 2]> {
        let &(row, across) = RACK.get(number.checked_sub(1)?)?;
        Some([
            across * self.pin.spacing,
            self.pin_line() + row * self.row_spacing(),
        ])
    }

    /// A pin's height (m): the profile's last height.
    pub fn pin_height(&self) -> f64 {
        self.pin.profile.last().map_or(0.0, |p| p[0])
    }

    /// A gutter's shape, centred on its middle line at lane height, `half_len` long either
    /// way along y: the circular arc through the lane's edge, the bottom (at
    /// [`AlleyDesc::gutter_depth`]) and the outer edge, as [`GUTTER_FACETS`] flat slabs, one
    /// facet at the bottom, so a ball in it rolls down the middle.
    pub fn gutter_shape(&self, half_len: f64) -> ShapeDesc {
        let (half, depth) = (self.gutter_width / 2.0, self.gutter_depth);
        // The arc's radius from its chord and sagitta.
        let rho = (half * half + depth * depth) / (2.0 * depth);
        let reach = (half / rho).asin();
        let n = GUTTER_FACETS;
        let point = |k: u32| {
            let a = -reach + 2.0 * reach * f64::from(k) / f64::from(n);
            (rho * a.sin(), rho - depth - rho * a.cos())
        };
        ShapeDesc::compound(
            (0..n)
                .map(|k| {
                    let (p, q) = (point(k), point(k + 1));
                    let points = [-half_len, half_len]
                        .into_iter()
                        .flat_map(|y| {
                            [
                                [p.0, y, p.1],
                                [q.0, y, q.1],
                                [p.0, y, p.1 - SLAB],
                                [q.0, y, q.1 - SLAB],
                            ]
                        })
                        .collect();
                    PartDesc::new(ShapeDesc::hull(points))
                })
                .collect(),
        )
    }

    /// The pin's shape: one frustum per neighbouring pair of profile points, each the hull
    /// of two regular polygons inscribed in the profile's circles.
    pub fn pin_shape(&self) -> ShapeDesc {
        let n = self.pin.sides;
        let ring = |[h, d]: [f64; 2]| -> Vec<[f64; 3]> {
            if d == 0.0 {
                return vec![[0.0, 0.0, h]];
            }
            (0..n)
                .map(|k| {
                    let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
                    [d / 2.0 * a.cos(), d / 2.0 * a.sin(), h]
                })
                .collect()
        };
        ShapeDesc::compound(
            self.pin
                .profile
                .windows(2)
                .map(|w| {
                    let mut points = ring(w[0]);
                    points.extend(ring(w[1]));
                    PartDesc::new(ShapeDesc::hull(points))
                })
                .collect(),
        )
    }

    /// The alley as a scene with the ball at rest on the foul line at `ball_x`: fixed lane,
    /// gutters, pit (and kickbacks), the ten pins standing on their spots, the ball. Bodies:
    /// `lane`, `gutter-left`, `gutter-right`, `gutter-wall-left`, `gutter-wall-right`, `pit`,
    /// `pit-back`, (`kickback-left`, `kickback-right`),
    /// `pin1` … `pin10`, `ball`; materials `lane`, `pin`, `ball`. The caller sets the ball's
    /// velocities, the duration and the frame rate.
    pub fn scene(&self, ball_x: f64) -> SceneDesc {
        let gap = PLACE_GAP_REL * self.collision_epsilon;
        let (w, gw) = (self.lane_width / 2.0, self.gutter_width);
        let (y0, y1) = (-APPROACH, self.deck_end());
        let slab = |name: &str, half: [f64; 3], at: [f64; 3]| {
            BodyDesc::fixed(name, ShapeDesc::cuboid(half))
                .at(at)
                .with_material("lane")
        };
        let (mid, half_len) = ((y0 + y1) / 2.0, (y1 - y0) / 2.0);
        let mut d = SceneDesc::new()
            .with_name("bowling")
            .with_collision_epsilon(self.collision_epsilon)
            .with_material_pair("ball", "lane", self.contacts.ball_lane)
            .with_material_pair("ball", "pin", self.contacts.ball_pin)
            .with_material_pair("pin", "pin", self.contacts.pin_pin)
            .with_material_pair("pin", "lane", self.contacts.pin_lane)
            .with_body(slab("lane", [w, half_len, SLAB], [0.0, mid, -SLAB]));
        for (name, side) in [("gutter-left", -1.0), ("gutter-right", 1.0)] {
            d = d.with_body(
                BodyDesc::fixed(name, self.gutter_shape(half_len))
                    .at([side * (w + gw / 2.0), mid, 0.0])
                    .with_material("lane"),
            );
        }
        // The gutters' outer walls: a gutter ball stays in its gutter.
        for (name, side) in [("gutter-wall-left", -1.0), ("gutter-wall-right", 1.0)] {
            let bottom = -self.gutter_depth;
            d = d.with_body(slab(
                name,
                [SLAB, half_len, (GUTTER_WALL_HEIGHT - bottom) / 2.0],
                [
                    side * (w + gw + SLAB),
                    mid,
                    (GUTTER_WALL_HEIGHT + bottom) / 2.0,
                ],
            ));
        }
        let pit_half_width = w + gw + 2.0 * SLAB + 1.0;
        d = d.with_body(slab(
            "pit",
            [pit_half_width, PIT_LENGTH / 2.0, SLAB],
            [0.0, y1 + PIT_LENGTH / 2.0, -PIT_DEPTH - SLAB],
        ));
        // The pit's back wall (the cushion): what falls into the pit stays there.
        d = d.with_body(slab(
            "pit-back",
            [pit_half_width, SLAB, (KICKBACK_HEIGHT + PIT_DEPTH) / 2.0],
            [
                0.0,
                y1 + PIT_LENGTH + SLAB,
                (KICKBACK_HEIGHT - PIT_DEPTH) / 2.0,
            ],
        ));
        if self.kickbacks {
            let (k0, k1) = (self.pin_line() - KICKBACK_LEAD, y1);
            let bottom = -PIT_DEPTH;
            for (name, side) in [("kickback-left", -1.0), ("kickback-right", 1.0)] {
                d = d.with_body(slab(
                    name,
                    [SLAB, (k1 - k0) / 2.0, (KICKBACK_HEIGHT - bottom) / 2.0],
                    [
                        side * (w + gw + 3.0 * SLAB),
                        (k0 + k1) / 2.0,
                        (KICKBACK_HEIGHT + bottom) / 2.0,
                    ],
                ));
            }
        }
        let pin = self.pin_shape();
        for number in 1..=PIN_COUNT {
            let Some([x, y]) = self.pin_spot(number) else {
                continue;
            };
            d = d.with_body(
                BodyDesc::new(format!("pin{number}"), pin.clone())
                    .at([x, y, gap])
                    .with_mass(self.pin.mass)
                    .with_material("pin"),
            );
        }
        d.with_body(
            BodyDesc::new("ball", ShapeDesc::sphere(self.ball.radius))
                .at([ball_x, 0.0, self.ball.radius + gap])
                .with_mass(self.ball.mass)
                .with_material("ball"),
        )
    }
}
