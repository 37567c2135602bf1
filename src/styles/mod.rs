//! Stylized renderings of a sample set (the paper's mosaic, strokes, Voronoi, …).
