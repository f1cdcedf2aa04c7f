#pragma once
/*!
  \file pattern.h
  \brief Calibration patterns: their text form (`--pattern`), their geometry and feature ids.

  Text form (docs/formats.md, "Patterns"):
  - `chessboard:COLSxROWS:SQUARE`: COLS x ROWS inner corners (at least 3 x 3), squares of SQUARE
    metres.
  - `apriltag:FAMILY:SIZE`: AprilTags of a family (36h11, 25h9, 16h5, circle21h7, circle49h12,
    custom48h12, standard41h12, standard52h13; "tag36h11" and any letter case are accepted), SIZE
    metres between the outer corners of the black border (ViSP's tagSize). For the families with a
    reversed border (circle*, custom*, standard*) SIZE is the side of the square the detector finds,
    libapriltag's `width_at_border` cells, i.e. the outer edge of the white border ring.
    Debian's ViSP 3.5 is built without the big families (circle49h12, custom48h12, standard41h12,
    standard52h13): they parse and render, but PatternDetector refuses them.

  Board frame `b`: origin at chessboard inner corner (row 0, col 0), X along the columns (to the
  right in the board's own picture), Y along the rows (down), Z into the board (away from a camera
  that faces it). The outer square beyond corner (0, 0) (top-left) is black. A chessboard has
  (COLS + 1) x (ROWS + 1) squares; square (i, j) (corners (i, j) .. (i + 1, j + 1) x SQUARE) is
  black iff i + j is even. It is symmetric under a half turn iff COLS + ROWS is even.

  Feature ids:
  - chessboard: inner corner (row, col) has id `row * COLS + col`, in the board's own grid, the
    same in every frame whatever order a detector returns.
  - AprilTag: tag `t` gives five features: id `5 t` its centre, `5 t + 1 .. 5 t + 4` its corners in
    ViSP's order (vpDetectorAprilTag::getPolygon, libapriltag's): the tag's own bottom-left,
    bottom-right, top-right, top-left corner of its bitmap (as apriltag_to_image() draws it, row 0
    on top), counter-clockwise as seen in the image. Verified on rendered tags (36h11, 25h9,
    circle21h7) against BoardLayout::features(). The centre is the image of the tag's centre (the
    intersection of the diagonals), not ViSP's getCog() (the corners' mean, biased by perspective).
    Pixels follow the usual convention (pixel centres at integers); libapriltag's half-pixel shift
    is removed by the detector.
*/
#include <Eigen/Core>
#include <string>
#include <vector>

namespace yawdepth {

/*! \brief A pattern, parsed from its `--pattern` text. */
struct PatternSpec {
  /*! \brief The kind of pattern. */
  enum class Kind { Chessboard, AprilTag };
  Kind kind = Kind::Chessboard; //!< the kind of pattern
  int cols = 0;            //!< chessboard inner corners along a row
  int rows = 0;            //!< chessboard inner corners along a column
  double square = 0;       //!< chessboard square size (m)
  std::string family;      //!< AprilTag family name, e.g. "36h11"
  double tag_size = 0;     //!< AprilTag size (m), outer edge of the black border

  /*! \brief Parse `chessboard:COLSxROWS:SQUARE` or `apriltag:FAMILY:SIZE`; throws yawdepth::Error. */
  static PatternSpec parse(const std::string &text);
  /*! \brief The text form. */
  std::string toString() const;
  /*! \brief Number of features of one chessboard (COLS * ROWS), 0 for AprilTag. */
  int chessboardCorners() const { return kind == Kind::Chessboard ? cols * rows : 0; }
};

/*!
  \brief The canonical family name ("36h11", "circle21h7", ...) of `name`, case-insensitive, with or
  without a leading "tag"; throws yawdepth::Error for a family not listed above.
*/
std::string normalizeAprilTagFamily(const std::string &name);

/*!
  \brief Geometry of an AprilTag family's bitmaps (libapriltag's apriltag_to_image()).

  A bitmap has `total_width` x `total_width` cells; the detected border square (the tag's `SIZE`)
  is the centred `width_at_border` x `width_at_border` cells, so a cell is SIZE / width_at_border
  and the bitmap reaches (total_width - width_at_border) / 2 cells beyond the border square (one
  white cell for 36h11, 25h9, 16h5; two cells of data and border for the circle, custom and standard
  families, whose border is reversed: SIZE is then the outer edge of the white border ring).
*/
struct AprilTagFamilyInfo {
  int ncodes = 0;          //!< number of tags (ids 0 .. ncodes - 1)
  int total_width = 0;     //!< bitmap side (cells)
  int width_at_border = 0; //!< side of the detected border square (cells)
};
/*! \brief Family geometry; throws yawdepth::Error for an unknown family. */
AprilTagFamilyInfo aprilTagFamilyInfo(const std::string &family);

/*! \brief AprilTag feature id of a tag's centre (`corner` = -1) or corner (0..3). */
inline long aprilTagFeatureId(int tag_id, int corner = -1) { return 5L * tag_id + 1 + corner; }

/*!
  \brief A physical board: the pattern and, for AprilTag, a grid of tags.

  AprilTag boards (for rendering and ground truth): `tags_x` x `tags_y` tags with ids
  `first_tag_id` + row * tags_x + col, tag (row, col) with its top-left outer corner at
  (col, row) * (tag_size + gap) in the board frame. The tag's bitmap (libapriltag's
  apriltag_to_image()) reaches beyond the border square by (total_width - width_at_border) / 2
  cells (see AprilTagFamilyInfo): one white cell for 36h11, 25h9, 16h5 (the default margin, 1/4
  tag for 36h11, is that ring plus one cell); for the reversed-border families the gap should be at
  least 2 x that overhang so that bitmaps do not overlap (where they do, the lower id wins).
  features(), extent() throw yawdepth::Error for an invalid layout or ids beyond the family.
*/
struct BoardLayout {
  PatternSpec pattern;        //!< the pattern
  int tags_x = 1;             //!< AprilTag grid: number of tags along a row
  int tags_y = 1;             //!< AprilTag grid: number of tags along a column
  double gap = 0;             //!< AprilTag spacing between tags (m)
  int first_tag_id = 0;       //!< AprilTag id of the first tag (row 0, column 0)
  double margin = 0;          //!< White margin around the pattern (m); 0 = one square / the bitmap's ring + one cell
  /*! Chessboard: width of the outer row and column of squares, around the inner corners (m); 0 = a
      full square. Many printed boards cut them narrower (OpenCV's sample board: about half). */
  double outer_square = 0;

  /*! \brief Every feature of the board: its id and position in the board frame (m). */
  std::vector<std::pair<long, Eigen::Vector3d>> features() const;
  /*!
    \brief Reflectance at board point (X, Y): 0 black, 1 white, or -1 outside the board.
    Used by the renderer.
  */
  double reflectance(double X, double Y) const;
  /*! \brief The board's extent in the board frame: (xmin, ymin, xmax, ymax) including the margin. */
  Eigen::Vector4d extent() const;
};

} // namespace yawdepth
