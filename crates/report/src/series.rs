//! The data of a line plot, shared by the report input and the sections that add plots of
//! their own (the schedule).

use serde::{Deserialize, Serialize};

/// A line plot rendered as inline SVG.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// x axis label (with unit).
    pub x_label: String,
    /// y axis label (with unit).
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
}

/// One curve of a [`Plot`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Points (x, y) in drawing order.
    pub points: Vec<[f64; 2]>,
}
