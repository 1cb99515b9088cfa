//! Every picture cellseq draws, in one place, with one embedded font: [`pictures`] of
//! instances, solutions, programs and drawings (`cellseq plot`), and the report's statistical
//! [`charts`] (box plots, anytime curves, facets, scaling; PNG, SVG and PDF).
//!
//! Text uses DejaVu Sans, embedded in the binary ([`FONT`], `assets/fonts/DejaVuSans.ttf`, free
//! licence in `assets/fonts/DejaVu-LICENSE.txt`) and registered with plotters' `ab_glyph`
//! feature by [`register_font`], so no system font package is needed.

pub mod charts;
pub mod pictures;

pub use pictures::{
    Panel, PictureFormat, bounds, drawing_panel, encode_png, plot, plot_panels, program_panel,
};

use plotters::style::{FontStyle, register_font as register};
use std::sync::Once;

/// The embedded font (DejaVu Sans, Bitstream Vera derived free licence).
pub const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The name plotters draws text with.
const FONT_NAME: &str = "sans-serif";
/// The family SVG output names: DejaVu Sans, with a generic fallback for SVG viewers.
pub(crate) const FAMILY: &str = "DejaVu Sans, sans-serif";

static REGISTER: Once = Once::new();

/// Registers the embedded DejaVu Sans as plotters' `sans-serif` and as the figures' family
/// (idempotent). Anything that draws with plotters in this build (e.g. criterion's HTML report
/// in benches) needs this, because the `ab_glyph` feature has no system-font fallback.
pub fn register_font() {
    REGISTER.call_once(|| {
        // The bytes are a valid TTF shipped with the crate; failure would leave text unrendered.
        let _ = register(FONT_NAME, FontStyle::Normal, FONT);
        let _ = register(FAMILY, FontStyle::Normal, FONT);
    });
}
