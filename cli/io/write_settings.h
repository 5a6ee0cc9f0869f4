#pragma once
// How the output files are encoded. The defaults are what every command writes; reference() is
// how they were first written (plain writers), kept so that bench_outputs can measure the
// writers against it in one run. Both give files with the same content (the same pixels, the
// same values); only PNG and SVG bytes differ between them.

namespace scanplan::cli {

/// zlib settings of a PNG: the compression level (0–9) and the libpng row filters
/// (PNG_FILTER_* bits).
struct PngSettings {
  /// Level 2 with the Up filter: on the figures (flat colours, maps repeated row after row)
  /// about 3× faster to encode than level 6 trying every filter, files 8–30 % larger.
  int level = 2;
  int filters = 0x20;  ///< PNG_FILTER_UP
};

struct WriteSettings {
  PngSettings png;
  /// The 3D pictures (path.png, cloud.png, certificate.png, cell.png: views on a white ground):
  /// level 2 without a row filter, ~15 % faster to encode than with the Up filter and 2–5 %
  /// smaller on them (the maps, row after row alike, keep `png`).
  PngSettings views{2, 0x08};  // PNG_FILTER_NONE
  /// SVG figures embed their raster as a PNG encoded with `png` (cairo's own encoder otherwise:
  /// level 6, every filter).
  bool svg_raster_png = true;
  /// Large binary files (PLY, npy) go to the file in pieces as they are formatted, without a
  /// copy of the whole file in memory (otherwise formatted into a string stream first).
  bool stream_binary = true;
  /// cloud.png's three point views are drawn from one set of points and colours in one pass over
  /// them (otherwise each view gets its own copy and its own pass).
  bool shared_views = true;

  /// The writers as they were: PNG level 6 with every filter, cairo's PNGs in the SVGs, PLY and
  /// npy built in memory, a copy of the points and a pass over them per view.
  static constexpr WriteSettings reference() {
    WriteSettings s;
    s.png = {6, 0xf8};  // PNG_ALL_FILTERS
    s.views = s.png;
    s.svg_raster_png = false;
    s.stream_binary = false;
    s.shared_views = false;
    return s;
  }
};

}  // namespace scanplan::cli
