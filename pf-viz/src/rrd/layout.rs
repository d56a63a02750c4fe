//! The layout a recording opens on, sent as blueprint archetypes.
//!
//! The SDK's builder (`rerun::blueprint`) arranges views but cannot set a view's properties,
//! and the viewer's defaults hide what these recordings are for:
//! - a time series on a sequence timeline longer than 2 000 opens on the ±1 000 around the
//!   time cursor (the dredger's 5 400 s cycle opened on its last 1 500 s);
//! - a 2-D view fits its data's bounding box with no margin, so points sit on the edges and
//!   their labels fall off, and a view whose scene moves (an ellipse shrinking as λ grows)
//!   zooms with it, which hides the motion;
//! - legends sit in the lower-left corner, over the curves that start there.
//!
//! So the layout is written here as the viewer stores it: a `ViewBlueprint` per view with
//! its `ViewContents` and property archetypes (`VisualBounds2D`, `TimeAxis`, `PlotLegend`)
//! under `view/<id>`, a `ContainerBlueprint` per container, the `ViewportBlueprint` and the
//! time panel, in a blueprint store that is then activated. Ids are fixed UUIDs numbered in
//! order, so a recording's layout is the same at every run.

use rerun::RecordingStream;
use rerun::RecordingStreamBuilder;
use rerun::external::re_log_types::BlueprintActivationCommand;
use rerun::external::re_sdk_types::blueprint::{archetypes as bp, components as bc};
use rerun::external::re_sdk_types::datatypes::{Range1D, Range2D, TimeRange};
use rerun::external::re_sdk_types::external::uuid::Uuid;

use super::APP_ID;

/// A corner for a time series' legend.
pub use bc::Corner2D as Corner;

/// A rectangle of a 2-D view's scene coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// `[min, max]` of x.
    pub x: [f64; 2],
    /// `[min, max]` of y.
    pub y: [f64; 2],
}

impl Bounds {
    /// The smallest rectangle holding `points`, widened by `margin` of its size on every side
    /// (a point or a line keeps a size of at least 1). `None` without a finite point.
    pub fn around(points: impl IntoIterator<Item = [f32; 2]>, margin: f64) -> Option<Bounds> {
        let mut b: Option<Bounds> = None;
        for p in points {
            let (x, y) = (f64::from(p[0]), f64::from(p[1]));
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            let r = b.get_or_insert(Bounds {
                x: [x, x],
                y: [y, y],
            });
            r.x = [r.x[0].min(x), r.x[1].max(x)];
            r.y = [r.y[0].min(y), r.y[1].max(y)];
        }
        b.map(|b| {
            let pad = |[lo, hi]: [f64; 2]| {
                let m = margin * (hi - lo).max(1.0);
                [lo - m, hi + m]
            };
            Bounds {
                x: pad(b.x),
                y: pad(b.y),
            }
        })
    }
}

/// One view of the layout.
#[derive(Debug, Clone)]
pub struct View {
    class: &'static str,
    name: String,
    origin: String,
    contents: Vec<String>,
    bounds: Option<Bounds>,
    whole_time: bool,
    legend: Option<Corner>,
}

impl View {
    fn new(class: &'static str, name: impl Into<String>, origin: impl Into<String>) -> Self {
        View {
            class,
            name: name.into(),
            origin: origin.into(),
            contents: vec!["$origin/**".into()],
            bounds: None,
            whole_time: false,
            legend: None,
        }
    }

    /// A 2-D view of the entities under `origin`.
    pub fn spatial_2d(name: impl Into<String>, origin: impl Into<String>) -> Self {
        View::new("2D", name, origin)
    }

    /// A time series of the scalars under `origin`.
    pub fn time_series(name: impl Into<String>, origin: impl Into<String>) -> Self {
        View::new("TimeSeries", name, origin)
    }

    /// Show the entities that `queries` select (`+ path/**`, `- path`) instead of everything
    /// under the origin.
    pub fn with_contents(mut self, queries: impl IntoIterator<Item = String>) -> Self {
        self.contents = queries.into_iter().collect();
        self
    }

    /// Open a 2-D view on `bounds` (the viewer letterboxes them to the view's shape), when
    /// there are any.
    pub fn with_bounds(mut self, bounds: Option<Bounds>) -> Self {
        self.bounds = bounds;
        self
    }

    /// Open a time series on the whole timeline, however long.
    pub fn with_whole_time(mut self) -> Self {
        self.whole_time = true;
        self
    }

    /// Put a time series' legend in `corner`.
    pub fn with_legend(mut self, corner: Corner) -> Self {
        self.legend = Some(corner);
        self
    }
}

/// A view, or views side by side, stacked, in a grid or in tabs.
#[derive(Debug, Clone)]
pub enum Node {
    /// One view.
    View(View),
    /// Several, arranged.
    Split {
        /// How the children are arranged.
        kind: bc::ContainerKind,
        /// The children, in order.
        children: Vec<Node>,
        /// Relative widths (horizontal) or heights (vertical).
        shares: Option<Vec<f32>>,
        /// Columns of a grid.
        columns: Option<u32>,
    },
}

impl From<View> for Node {
    fn from(v: View) -> Self {
        Node::View(v)
    }
}

fn split(kind: bc::ContainerKind, children: impl IntoIterator<Item = Node>) -> Node {
    Node::Split {
        kind,
        children: children.into_iter().collect(),
        shares: None,
        columns: None,
    }
}

/// Children left to right.
pub fn horizontal(children: impl IntoIterator<Item = Node>) -> Node {
    split(bc::ContainerKind::Horizontal, children)
}

/// Children top to bottom.
pub fn vertical(children: impl IntoIterator<Item = Node>) -> Node {
    split(bc::ContainerKind::Vertical, children)
}

/// Children as tabs, the first one shown.
pub fn tabs(children: impl IntoIterator<Item = Node>) -> Node {
    split(bc::ContainerKind::Tabs, children)
}

/// Children in a grid of `columns` columns.
pub fn grid(columns: u32, children: impl IntoIterator<Item = Node>) -> Node {
    Node::Split {
        kind: bc::ContainerKind::Grid,
        children: children.into_iter().collect(),
        shares: None,
        columns: Some(columns),
    }
}

impl Node {
    /// Relative widths of a horizontal split's children, or heights of a vertical one's.
    pub fn with_shares(mut self, s: impl IntoIterator<Item = f32>) -> Self {
        if let Node::Split { shares, .. } = &mut self {
            *shares = Some(s.into_iter().collect());
        }
        self
    }
}

/// Numbers the layout's views and containers in the order they are logged.
struct Ids(u128);

impl Ids {
    /// The next id, with "pf" in its top bytes so that it reads as this tool's.
    fn next(&mut self) -> Uuid {
        self.0 += 1;
        Uuid::from_u128((0x7066 << 112) | self.0)
    }
}

/// Log `node` (children first) into the blueprint stream `bp`; returns its path and id.
fn log_node(
    bp: &RecordingStream,
    ids: &mut Ids,
    node: &Node,
) -> rerun::RecordingStreamResult<(String, Uuid)> {
    let id = ids.next();
    match node {
        Node::View(v) => {
            let path = format!("view/{id}");
            bp.log(
                format!("{path}/ViewContents"),
                &bp::ViewContents::new(
                    v.contents
                        .iter()
                        .map(|q| bc::QueryExpression(q.as_str().into())),
                ),
            )?;
            bp.log(
                path.as_str(),
                &bp::ViewBlueprint::new(bc::ViewClass(v.class.into()))
                    .with_display_name(v.name.as_str())
                    .with_space_origin(v.origin.as_str()),
            )?;
            if let Some(b) = v.bounds {
                bp.log(
                    format!("{path}/VisualBounds2D"),
                    &bp::VisualBounds2D::new(Range2D {
                        x_range: Range1D(b.x),
                        y_range: Range1D(b.y),
                    }),
                )?;
            }
            if v.whole_time {
                bp.log(
                    format!("{path}/TimeAxis"),
                    &bp::TimeAxis::new().with_view_range(TimeRange::EVERYTHING),
                )?;
            }
            if let Some(corner) = v.legend {
                bp.log(
                    format!("{path}/PlotLegend"),
                    &bp::PlotLegend::new().with_corner(corner),
                )?;
            }
            Ok((path, id))
        }
        Node::Split {
            kind,
            children,
            shares,
            columns,
        } => {
            let paths = children
                .iter()
                .map(|c| log_node(bp, ids, c).map(|(path, _)| path))
                .collect::<rerun::RecordingStreamResult<Vec<_>>>()?;
            let path = format!("container/{id}");
            let mut c = bp::ContainerBlueprint::new(*kind)
                .with_contents(paths.iter().map(|p| bc::IncludedContent(p.as_str().into())));
            if let Some(s) = shares {
                let s = s.iter().copied();
                c = match kind {
                    bc::ContainerKind::Vertical => c.with_row_shares(s.map(bc::RowShare::from)),
                    _ => c.with_col_shares(s.map(bc::ColumnShare::from)),
                };
            }
            if let Some(n) = columns {
                c = c.with_grid_columns(bc::GridColumns::from(*n));
            }
            bp.log(path.as_str(), &c)?;
            Ok((path, id))
        }
    }
}

/// Send `root` as the layout of `rec`, made active and the default for [`APP_ID`], with the
/// time panel on `timeline` when given.
///
/// # Errors
/// A Rerun error.
pub fn send(
    rec: &RecordingStream,
    root: &Node,
    timeline: Option<&str>,
) -> rerun::RecordingStreamResult<()> {
    let (bp, storage) = RecordingStreamBuilder::new(APP_ID).blueprint().memory()?;
    // The viewer reads blueprint data on this timeline.
    bp.set_time_sequence("blueprint", 0);
    let mut ids = Ids(0);
    // A view at the root goes into tabs of its own, as the viewer expects a container there.
    let root = match root {
        Node::View(_) => tabs([root.clone()]),
        split => split.clone(),
    };
    let (_, root_id) = log_node(&bp, &mut ids, &root)?;
    bp.log(
        "viewport",
        &bp::ViewportBlueprint::new().with_root_container(bc::RootContainer(root_id.into())),
    )?;
    if let Some(t) = timeline {
        bp.log(
            "time_panel",
            &bp::TimePanelBlueprint::new().with_timeline(t),
        )?;
    }
    let store = bp.store_info().map(|i| i.store_id);
    let msgs = storage.take();
    if let Some(blueprint_id) = store {
        rec.send_blueprint(
            msgs,
            BlueprintActivationCommand {
                blueprint_id,
                make_active: true,
                make_default: true,
            },
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_hold_every_finite_point_with_a_margin() {
        let b = Bounds::around([[0.0, -2.0], [10.0, 2.0], [f32::NAN, 1e9]], 0.1).unwrap();
        assert_eq!(b.x, [-1.0, 11.0]);
        assert!(
            (b.y[0] + 2.4).abs() < 1e-12 && (b.y[1] - 2.4).abs() < 1e-12,
            "{b:?}"
        );
        // A single point keeps a unit-sized box.
        let p = Bounds::around([[3.0, 4.0]], 0.5).unwrap();
        assert_eq!((p.x, p.y), ([2.5, 3.5], [3.5, 4.5]));
        assert_eq!(Bounds::around([[f32::INFINITY, 0.0]], 0.1), None);
    }

    #[test]
    fn ids_are_distinct_and_numbered_in_order() {
        let mut ids = Ids(0);
        let (a, b) = (ids.next(), ids.next());
        assert_ne!(a, b);
        assert_eq!(a.to_string(), "70660000-0000-0000-0000-000000000001");
        assert_eq!(b.as_u128() - a.as_u128(), 1);
    }
}
