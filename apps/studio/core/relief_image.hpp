#pragma once
/// The paper's relief as an image for the paper view: the height field of the world
/// configuration sampled at every pixel of a rectangle of the paper, drawn as paper-coloured
/// gray levels (high = light, low = darker). Computed once and cached by the view. Not for
/// the servo thread.

#include <QImage>

#include "hattr/render/height_field.hpp"

namespace hattr::studio {

/// The relief over (x_min, y_min)–(x_max, y_max) [m] as a width × height image, row 0 at
/// y_max (the top of the view). Heights map linearly to gray between mean ± 2.5 standard
/// deviations. A flat field gives a plain paper colour.
QImage reliefImage(const render::HeightField& relief, double x_min_m, double y_min_m, double x_max_m, double y_max_m,
                   int width_px, int height_px);

/// The plain paper colour (the relief's highest level).
QColor paperColour();

}  // namespace hattr::studio
