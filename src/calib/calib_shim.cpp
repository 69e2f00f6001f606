/* Board detection and calibration on OpenCV 4.6 (the aruco module's pre-4.7 API). */
#include "calib/calib_shim.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "util/errbuf.h"
#include "util/shim_guard.hpp"

namespace {

/*
 * Detection runs on a copy scaled down to this many pixels on the long side: marker and
 * chessboard finding cost grows with the area, and 1280 px still resolves a board that is
 * usable for calibration. Corners are then refined in the full image.
 */
const int DETECT_MAX_SIDE = 1280;

/*
 * Each Levenberg-Marquardt step of OpenCV's calibration costs a dense solve cubic in 6 x views
 * parameters (0.5 s at 85 views here); OpenCV's default runs all 30 steps unless the update is
 * below DBL_EPSILON. A relative update of 1e-8 moves fx by under 1e-5 px.
 */
const cv::TermCriteria SOLVER_STOP(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 1e-8);

const cv::TermCriteria SUBPIX_STOP(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 0.001);

/*
 * Chessboard corners are refined in a window of 0.4 of the shortest spacing between
 * neighbours in a row: the nearest other saddle is a square away, so it never spans two.
 */
void refine_chessboard(const cv::Mat &grey, std::vector<cv::Point2f> &pts, int cols)
{
	double spacing = 1e9;
	for (size_t i = 1; i < pts.size(); i++)
		if (i % (size_t)cols != 0)
			spacing = std::min(spacing, cv::norm(pts[i] - pts[i - 1]));
	int half = std::clamp((int)(spacing * 0.4), 2, 11);
	cv::cornerSubPix(grey, pts, cv::Size(half, half), cv::Size(-1, -1), SUBPIX_STOP);
}

} // namespace

using Quads = std::vector<std::vector<cv::Point2f>>;

/*
 * Everything a frame's detection writes lives here and keeps its capacity from frame to frame:
 * after the first few frames the detection path allocates only what OpenCV allocates inside.
 */
struct mvod_calib_det {
	mvod_board board;
	cv::Ptr<cv::aruco::Dictionary> dict;
	cv::Ptr<cv::aruco::CharucoBoard> charuco;
	cv::Ptr<cv::aruco::DetectorParameters> params;
	cv::Mat grey;        /* a BGR frame converted */
	cv::Mat small;
	cv::Mat inverted;    /* small, white on black */
	cv::Mat thumb;       /* of the last examined frame */
	cv::Mat next_thumb;  /* of this one */
	Quads markers, rejected, inv_markers, inv_rejected;
	std::vector<int> ids, inv_ids, pt_ids;
	std::vector<cv::Point2f> pts, layout, projected, hull_img, hull_layout;
	std::vector<double> residuals;
};

namespace {

/*
 * A 40 x 30 thumbnail averages each cell over 16 x 16 px or more, leaving sensor noise well
 * under a grey level; a board that moves by 1 % of the image changes it by several.
 */
const cv::Size THUMB(40, 30);
const double REPEAT_GREY_LEVELS = 1.0;

/* img as grey: a view of it, or its conversion in d.grey. */
cv::Mat grey_of(mvod_calib_det &d, const mvod_image &img)
{
	cv::Mat m(img.h, img.w, img.fmt == MVOD_PIX_BGR ? CV_8UC3 : CV_8UC1, img.data,
		  (size_t)img.stride);
	if (img.fmt == MVOD_PIX_GREY)
		return m;
	cv::cvtColor(m, d.grey, cv::COLOR_BGR2GRAY);
	return d.grey;
}

bool is_repeat(mvod_calib_det &d, const cv::Mat &grey)
{
	cv::resize(grey, d.next_thumb, THUMB, 0, 0, cv::INTER_AREA);
	if (!d.thumb.empty() &&
	    cv::norm(d.next_thumb, d.thumb, cv::NORM_L1) / THUMB.area() < REPEAT_GREY_LEVELS)
		return true;
	cv::swap(d.thumb, d.next_thumb);
	return false;
}

/* The grey image and a copy no larger than DETECT_MAX_SIDE; returns the copy's scale. */
double detection_image(mvod_calib_det &d, const cv::Mat &grey)
{
	double s = std::min(1.0, (double)DETECT_MAX_SIDE / std::max(grey.cols, grey.rows));
	if (s < 1.0)
		cv::resize(grey, d.small, cv::Size(), s, s, cv::INTER_AREA);
	else
		d.small = grey;
	return s;
}

void store_corners(const std::vector<cv::Point2f> &pts, const std::vector<int> *ids,
		   mvod_calib_found &f)
{
	f.n = (int)pts.size();
	for (int i = 0; i < f.n; i++) {
		f.ids[i] = ids ? (*ids)[i] : i;
		f.xy[2 * i] = pts[i].x;
		f.xy[2 * i + 1] = pts[i].y;
	}
}

void detect_chessboard(mvod_calib_det &d, const cv::Mat &grey, mvod_calib_found &f)
{
	double s = detection_image(d, grey);
	cv::Size pattern(d.board.cols, d.board.rows);
	std::vector<cv::Point2f> &pts = d.pts;
	bool found = cv::findChessboardCornersSB(d.small, pattern, pts, cv::CALIB_CB_NORMALIZE_IMAGE);
	if (!found)
		found = cv::findChessboardCorners(d.small, pattern, pts,
						  cv::CALIB_CB_ADAPTIVE_THRESH |
							  cv::CALIB_CB_NORMALIZE_IMAGE |
							  cv::CALIB_CB_FAST_CHECK);
	if (!found)
		return;
	for (auto &p : pts)
		p *= 1.0 / s;
	/* SB corners are already sub-pixel in the image they came from; refine the rest and upscaled ones. */
	refine_chessboard(grey, pts, d.board.cols);
	store_corners(pts, nullptr, f);
}

/* Moves the markers on the board to the front of d.markers, in full-image pixels; counts strays. */
void keep_on_board(mvod_calib_det &d, double s, mvod_calib_found &f)
{
	int on_board = (int)d.charuco->ids.size();
	size_t kept = 0;
	for (size_t i = 0; i < d.ids.size(); i++) {
		f.max_id = std::max(f.max_id, d.ids[i]);
		if (d.ids[i] >= on_board) {
			f.stray++;
			continue;
		}
		for (auto &p : d.markers[i])
			p *= 1.0 / s;
		d.markers[kept].swap(d.markers[i]);
		d.ids[kept++] = d.ids[i];
	}
	d.markers.resize(kept);
	d.ids.resize(kept);
}

/* Markers of the board's dictionary into d.markers and d.ids, in full-image pixels. */
void find_markers(mvod_calib_det &d, const cv::Mat &grey, mvod_calib_found &f)
{
	double s = detection_image(d, grey);
	cv::aruco::detectMarkers(d.small, d.dict, d.markers, d.ids, d.params, d.rejected);
	/*
	 * A board printed white-on-black (or shown inverted on a screen) is still a board. OpenCV's
	 * detectInvertedMarker would look for both at once, but it loses markers of normal boards
	 * (13 of 17 on some mvod-synth views), so the inverted image is only tried when the
	 * normal one shows too few markers to interpolate corners from.
	 */
	if (d.ids.size() < 2) {
		cv::bitwise_not(d.small, d.inverted);
		cv::aruco::detectMarkers(d.inverted, d.dict, d.inv_markers, d.inv_ids, d.params,
					 d.inv_rejected);
		if (d.inv_ids.size() > d.ids.size()) {
			d.markers.swap(d.inv_markers);
			d.ids.swap(d.inv_ids);
			d.rejected.swap(d.inv_rejected);
		}
	}
	keep_on_board(d, s, f);
	for (auto &r : d.rejected)
		for (auto &p : r)
			p *= 1.0 / s;
	if (!d.ids.empty())
		cv::aruco::refineDetectedMarkers(grey, d.charuco, d.markers, d.ids, d.rejected);
	f.markers = (int)d.ids.size();
}

/*
 * Whether corners sit where one homography of the board layout puts them. A board whose
 * COLSxROWS differs from the spec (7x5 for 5x7) still yields markers and corners, but placed
 * by the wrong layout, a square or more off: calibrating on them gives nonsense. Half a square
 * of median residual leaves room for strong lens distortion.
 */
bool fits_layout(mvod_calib_det &d)
{
	const std::vector<cv::Point2f> &pts = d.pts;
	if (pts.size() < 5)
		return true;
	d.layout.clear();
	for (int id : d.pt_ids) {
		double p[3];
		mvod_board_corner(&d.board, id, p);
		d.layout.emplace_back((float)p[0], (float)p[1]);
	}
	cv::Mat H = cv::findHomography(d.layout, pts, 0);
	if (H.empty())
		return false;
	cv::perspectiveTransform(d.layout, d.projected, H);
	std::vector<double> &res = d.residuals;
	res.clear();
	for (size_t i = 0; i < pts.size(); i++)
		res.push_back(cv::norm(d.projected[i] - pts[i]));
	std::nth_element(res.begin(), res.begin() + (long)res.size() / 2, res.end());
	cv::convexHull(pts, d.hull_img);
	cv::convexHull(d.layout, d.hull_layout);
	double px_per_m = std::sqrt(cv::contourArea(d.hull_img) /
				    std::max(cv::contourArea(d.hull_layout), 1e-12));
	return res[res.size() / 2] < 0.5 * d.board.square_m * px_per_m;
}

/*
 * Each ChArUco corner is refined in a window that keeps the detected marker corners out: they
 * are the nearest other features (a quarter of a square away diagonally when marker = square / 2,
 * nearer when the print's markers are larger than the spec says), and a window that reaches one
 * drags the saddle towards it. 0.75 of the Chebyshev distance to the nearest marker corner was
 * best of 0.5 / 0.75 / 0.9 on mvod-synth views (RMS 0.049 px against exact corners) and matches
 * OpenCV's reference RMS on its real photos (0.182 px).
 */
void refine_charuco(const cv::Mat &grey, const Quads &markers, std::vector<cv::Point2f> &pts)
{
	const double margin = 0.75;
	for (auto &p : pts) {
		double chebyshev = 1e9;
		for (const auto &m : markers)
			for (const auto &c : m)
				chebyshev = std::min(chebyshev, (double)std::max(std::abs(c.x - p.x), std::abs(c.y - p.y)));
		int half = std::clamp((int)(chebyshev * margin), 2, 11);
		/* Refined in place, through a header on the one point. */
		cv::cornerSubPix(grey, cv::Mat(1, 1, CV_32FC2, &p), cv::Size(half, half),
				 cv::Size(-1, -1), SUBPIX_STOP);
	}
}

void detect_charuco(mvod_calib_det &d, const cv::Mat &grey, mvod_calib_found &f)
{
	find_markers(d, grey, f);
	if (d.ids.empty())
		return;
	cv::aruco::interpolateCornersCharuco(d.markers, d.ids, grey, d.charuco, d.pts, d.pt_ids);
	/*
	 * OpenCV 4.6 returns its refined corners shifted by (+0.5, +0.5) px (opencv#25539, fixed
	 * upstream in 2026), which would bias cx and cy: 0.71 px mean error on mvod-synth views.
	 * Refining again from there converges on the saddle itself, whichever OpenCV this runs on.
	 */
	refine_charuco(grey, d.markers, d.pts);
	f.mislaid = !fits_layout(d);
	if (!f.mislaid)
		store_corners(d.pts, &d.pt_ids, f);
}

/* "a chessboard with CxR inner corners" when one of any size is in view; fits: that board. */
bool find_any_chessboard(const mvod_calib_det &d, const cv::Mat &grey, mvod_board &fits,
			 char *what, size_t len)
{
	std::vector<cv::Point2f> pts;
	cv::Mat meta;
	if (!cv::findChessboardCornersSB(grey, cv::Size(3, 3), pts, cv::CALIB_CB_LARGER, meta) ||
	    meta.empty())
		return false;
	std::snprintf(what, len, "a chessboard with %dx%d inner corners", meta.cols, meta.rows);
	fits = mvod_board{};
	fits.kind = MVOD_BOARD_CHESSBOARD;
	fits.cols = meta.cols;
	fits.rows = meta.rows;
	fits.square_m = d.board.square_m;
	return true;
}

/* Markers of another dictionary; fits: the searched ChArUco board in that dictionary. */
bool find_other_dictionary(const mvod_calib_det &d, const cv::Mat &grey, mvod_board &fits,
			   char *what, size_t len)
{
	auto params = cv::aruco::DetectorParameters::create();
	for (int k = 0; k < mvod_board_dict_count(); k++) {
		if (d.board.kind == MVOD_BOARD_CHARUCO &&
		    mvod_board_dict_family(k) == mvod_board_dict_family(d.board.dict))
			continue;
		std::vector<std::vector<cv::Point2f>> corners;
		std::vector<int> ids;
		cv::aruco::detectMarkers(grey, cv::aruco::getPredefinedDictionary(k), corners, ids, params);
		/* One or two hits can be chance codes in texture; a board shows many. */
		if (ids.size() >= 4) {
			std::snprintf(what, len, "%zu markers of %s%s", ids.size(), mvod_board_dict_name(k),
				      mvod_board_dict_family_size(k) > 1
					      ? " (or a larger dictionary of its family)"
					      : "");
			/* A chessboard spec says nothing of the ChArUco board's size: no spec then. */
			if (d.board.kind == MVOD_BOARD_CHARUCO) {
				fits = d.board;
				fits.dict = k;
				std::snprintf(fits.dict_name, sizeof(fits.dict_name), "%s",
					      mvod_board_dict_name(k));
			}
			return true;
		}
	}
	return false;
}

} // namespace

extern "C" int mvod_calib_det_create(const struct mvod_board *b, struct mvod_calib_det **out)
{
	*out = nullptr;
	return mvod_guarded([&] {
		auto d = std::make_unique<mvod_calib_det>();
		d->board = *b;
		if (b->kind == MVOD_BOARD_CHARUCO) {
			d->dict = cv::aruco::getPredefinedDictionary(b->dict);
			d->charuco = cv::aruco::CharucoBoard::create(b->cols, b->rows, (float)b->square_m,
								     (float)b->marker_m, d->dict);
			d->params = cv::aruco::DetectorParameters::create();
			/*
			 * No sub-pixel refinement of the marker corners: they only seed the corner
			 * interpolation, and on small markers its window reaches the chessboard
			 * corner next to them and drags them there (12 px corner errors).
			 */
			d->params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
		}
		*out = d.release();
		return 0;
	});
}

extern "C" void mvod_calib_det_destroy(struct mvod_calib_det *d)
{
	delete d;
}

extern "C" int mvod_calib_detect(struct mvod_calib_det *d, const struct mvod_image *img,
				 struct mvod_calib_found *f)
{
	f->n = f->markers = f->stray = 0;
	f->max_id = -1;
	f->mislaid = false;
	return mvod_guarded([&] {
		cv::Mat grey = grey_of(*d, *img);
		f->repeat = is_repeat(*d, grey);
		if (f->repeat)
			return 0;
		if (d->board.kind == MVOD_BOARD_CHARUCO)
			detect_charuco(*d, grey, *f);
		else
			detect_chessboard(*d, grey, *f);
		return 0;
	});
}

extern "C" int mvod_calib_diagnose(struct mvod_calib_det *d, const struct mvod_image *img,
				   struct mvod_board *fits, char *what, size_t len)
{
	what[0] = '\0';
	fits->cols = 0;
	return mvod_guarded([&] {
		cv::Mat grey = grey_of(*d, *img);
		detection_image(*d, grey);
		if (!find_other_dictionary(*d, d->small, *fits, what, len))
			find_any_chessboard(*d, d->small, *fits, what, len);
		return 0;
	});
}

namespace {

struct Views {
	std::vector<std::vector<cv::Point3f>> obj;
	std::vector<std::vector<cv::Point2f>> img;
};

Views to_views(const mvod_board &b, const mvod_calib_obs *v, int n)
{
	Views out;
	out.obj.resize(n);
	out.img.resize(n);
	for (int i = 0; i < n; i++) {
		for (int k = 0; k < v[i].n; k++) {
			double p[3];
			mvod_board_corner(&b, v[i].ids[k], p);
			out.obj[i].emplace_back((float)p[0], (float)p[1], (float)p[2]);
			out.img[i].emplace_back(v[i].xy[2 * k], v[i].xy[2 * k + 1]);
		}
	}
	return out;
}

void store_camera(const cv::Mat &K, const cv::Mat &D, int n_dist, mvod_camera &cam)
{
	cam.fx = K.at<double>(0, 0);
	cam.fy = K.at<double>(1, 1);
	cam.cx = K.at<double>(0, 2);
	cam.cy = K.at<double>(1, 2);
	cam.n_dist = n_dist;
	for (int i = 0; i < n_dist; i++)
		cam.dist[i] = D.at<double>(i);
}

void store_poses(const std::vector<cv::Mat> &rvecs, const std::vector<cv::Mat> &tvecs, double *pose)
{
	for (size_t i = 0; i < rvecs.size(); i++)
		for (int k = 0; k < 3; k++) {
			pose[6 * i + k] = rvecs[i].at<double>(k);
			pose[6 * i + 3 + k] = tvecs[i].at<double>(k);
		}
}

void fit_pinhole(const Views &v, cv::Size size, bool rational, mvod_calib_fit &fit)
{
	cv::Mat K, D, std_in, std_ex, per_view;
	std::vector<cv::Mat> rvecs, tvecs;
	int flags = rational ? cv::CALIB_RATIONAL_MODEL : 0;
	fit.rms_px = cv::calibrateCamera(v.obj, v.img, size, K, D, rvecs, tvecs, std_in, std_ex,
					 per_view, flags, SOLVER_STOP);
	store_camera(K, D, rational ? 8 : 5, fit.cam);
	store_poses(rvecs, tvecs, fit.view_pose);
	for (size_t i = 0; i < v.obj.size(); i++)
		fit.view_rms_px[i] = per_view.at<double>((int)i);
	/* stdDeviationsIntrinsics: fx fy cx cy, then the coefficients in OpenCV order. */
	fit.has_std = true;
	for (int i = 0; i < 4; i++)
		fit.std_K[i] = std_in.at<double>(i);
	for (int i = 0; i < fit.cam.n_dist; i++)
		fit.std_dist[i] = std_in.at<double>(4 + i);
}

/*
 * cv::fisheye::calibrate starts from f = max(w, h) / pi, an equidistant lens seeing 180 deg
 * across the image; for a narrower lens (fx 500 on 640 px) its initial board poses degenerate
 * and it fails (InitExtrinsics asserts). A pinhole fit with radial terms is close enough to any
 * lens the pinhole model can still describe to start it from there; when even that fails, the
 * lens is wide and OpenCV's own start suits it.
 */
bool pinhole_guess(const Views &v, cv::Size size, cv::Matx33d &K)
{
	try {
		cv::Mat K0, D0;
		std::vector<cv::Mat> r, t;
		cv::calibrateCamera(v.obj, v.img, size, K0, D0, r, t,
				    cv::CALIB_ZERO_TANGENT_DIST | cv::CALIB_FIX_K3, SOLVER_STOP);
		K = cv::Matx33d(K0);
		return K(0, 0) > 0 && K(1, 1) > 0 && std::isfinite(K(0, 0) + K(1, 1) + K(0, 2) + K(1, 2));
	} catch (const cv::Exception &) {
		return false;
	}
}

/* cv::fisheye::calibrate reports neither per-view errors nor deviations: errors are recomputed. */
void fit_fisheye(const Views &v, cv::Size size, mvod_calib_fit &fit)
{
	cv::Matx33d K;
	cv::Vec4d D;
	std::vector<cv::Mat> rvecs, tvecs;
	int flags = cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW;
	if (pinhole_guess(v, size, K))
		flags |= cv::fisheye::CALIB_USE_INTRINSIC_GUESS;
	cv::fisheye::calibrate(v.obj, v.img, size, K, D, rvecs, tvecs, flags,
			       cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10));
	store_camera(cv::Mat(K), cv::Mat(D), 4, fit.cam);
	store_poses(rvecs, tvecs, fit.view_pose);
	double sum = 0;
	size_t total = 0;
	for (size_t i = 0; i < v.obj.size(); i++) {
		std::vector<cv::Point2f> proj;
		cv::fisheye::projectPoints(v.obj[i], proj, rvecs[i], tvecs[i], K, D);
		double e = 0;
		for (size_t k = 0; k < proj.size(); k++) {
			cv::Point2f r = proj[k] - v.img[i][k];
			e += r.dot(r);
		}
		fit.view_rms_px[i] = std::sqrt(e / (double)proj.size());
		sum += e;
		total += proj.size();
	}
	fit.rms_px = std::sqrt(sum / (double)total);
	fit.has_std = false;
}

} // namespace

extern "C" int mvod_calib_solve(const struct mvod_board *b, const struct mvod_calib_obs *v, int n,
			      int w, int h, enum mvod_cam_model model, bool rational,
			      struct mvod_calib_fit *fit, char *err, size_t errlen)
{
	int ret = mvod_guarded([&] {
		Views views = to_views(*b, v, n);
		fit->cam.width = w;
		fit->cam.height = h;
		fit->cam.model = model;
		if (model == MVOD_CAM_FISHEYE_KB4)
			fit_fisheye(views, cv::Size(w, h), *fit);
		else
			fit_pinhole(views, cv::Size(w, h), rational, *fit);
		return std::isfinite(fit->rms_px) && fit->cam.fx > 0 && fit->cam.fy > 0 ? 0 : -EDOM;
	});
	if (ret)
		mvod_errf(err, errlen, ret,
			  "the %s calibration did not converge on %d views (the views may be too alike, "
			  "or the board spec may not match the board)",
			  mvod_cam_model_name(model), n);
	return ret;
}

extern "C" int mvod_calib_rough_tilts(const struct mvod_board *b, const struct mvod_calib_obs *v,
				      int n, int w, int h, double *rvecs)
{
	return mvod_guarded([&] {
		Views views = to_views(*b, v, n);
		/* Homographies of a couple of hundred views pin down a rough K as well as all of them. */
		Views sample;
		int step = std::max(1, n / 200);
		for (int i = 0; i < n; i += step) {
			sample.obj.push_back(views.obj[i]);
			sample.img.push_back(views.img[i]);
		}
		cv::Mat K = cv::initCameraMatrix2D(sample.obj, sample.img, cv::Size(w, h));
		for (int i = 0; i < n; i++) {
			cv::Vec3d r(0, 0, 0), t;
			cv::solvePnP(views.obj[i], views.img[i], K, cv::noArray(), r, t, false,
				     cv::SOLVEPNP_IPPE);
			for (int k = 0; k < 3; k++)
				rvecs[3 * i + k] = r[k];
		}
		return 0;
	});
}

namespace {

/* The view's corners as normalised image coordinates (x/z, y/z), the lens removed. */
std::vector<cv::Point2d> normalised(const std::vector<cv::Point2f> &px, const mvod_camera &cam)
{
	const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
	const cv::Mat D(1, cam.n_dist, CV_64F, const_cast<double *>(cam.dist));
	std::vector<cv::Point2d> in(px.begin(), px.end()), out;
	if (cam.model == MVOD_CAM_FISHEYE_KB4)
		cv::fisheye::undistortPoints(in, out, K, D);
	else
		cv::undistortPoints(in, out, K, cam.n_dist ? D : cv::Mat());
	return out;
}

/* Reprojection RMS in pixels through the camera's own lens model. */
double pose_rms_px(const std::vector<cv::Point3f> &obj, const std::vector<cv::Point2f> &px,
		   const cv::Vec3d &r, const cv::Vec3d &t, const mvod_camera &cam)
{
	const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
	const cv::Mat D(1, cam.n_dist, CV_64F, const_cast<double *>(cam.dist));
	std::vector<cv::Point2f> proj;
	if (cam.model == MVOD_CAM_FISHEYE_KB4)
		cv::fisheye::projectPoints(obj, proj, r, t, K, D);
	else
		cv::projectPoints(obj, r, t, K, cam.n_dist ? D : cv::Mat(), proj);
	double e = 0;
	for (size_t k = 0; k < proj.size(); k++) {
		cv::Point2f d = proj[k] - px[k];
		e += d.dot(d);
	}
	return std::sqrt(e / (double)proj.size());
}

} // namespace

extern "C" int mvod_calib_board_pose(const struct mvod_board *b, const struct mvod_calib_obs *v,
				     const struct mvod_camera *cam, double sigma_px,
				     struct mvod_calib_pose *out)
{
	return mvod_guarded([&] {
		Views views = to_views(*b, v, 1);
		std::vector<cv::Point2d> xn = normalised(views.img[0], *cam);
		std::vector<cv::Point3d> obj(views.obj[0].begin(), views.obj[0].end());
		/* IPPE: the planar solver, then Levenberg-Marquardt on all corners. */
		cv::Vec3d r, t;
		const cv::Matx33d I = cv::Matx33d::eye();
		if (!cv::solvePnP(obj, xn, I, cv::noArray(), r, t, false, cv::SOLVEPNP_IPPE))
			return -EDOM;
		cv::solvePnPRefineLM(obj, xn, I, cv::noArray(), r, t);
		/* Covariance sigma^2 (J^T J)^-1 of (rvec, tvec), sigma in normalised units. */
		std::vector<cv::Point2d> proj;
		cv::Mat J;
		cv::projectPoints(obj, r, t, I, cv::noArray(), proj, J);
		const double s = sigma_px / std::sqrt(cam->fx * cam->fy);
		cv::Mat JtJ = J.colRange(0, 6).t() * J.colRange(0, 6), cov;
		if (cv::invert(JtJ, cov, cv::DECOMP_SVD) <= 0)
			return -EDOM;
		cov *= s * s;
		for (int k = 0; k < 3; k++) {
			out->rvec[k] = r[k];
			out->tvec[k] = t[k];
		}
		for (int k = 0; k < 36; k++)
			out->cov[k] = cov.at<double>(k / 6, k % 6);
		out->rms_px = pose_rms_px(views.obj[0], views.img[0], r, t, *cam);
		return std::isfinite(out->rms_px) ? 0 : -EDOM;
	});
}
