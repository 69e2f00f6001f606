#include "mvod/view.h"

#include <cerrno>
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>

#include "mvod/plot.h"
#include "util/errbuf.h"
#include "util/image_file.h"
#include "util/shim_guard.hpp"

namespace {

/* The plot on the left, the panel of numbers on its right. */
const int PANEL_W = 340;
const int CANVAS_W = MVOD_PLOT_WIDTH + PANEL_W, CANVAS_H = MVOD_PLOT_HEIGHT;
const int MARGIN = 16, ROW_H = 25;
const int COMPASS_R = 55;
const int FONT = cv::FONT_HERSHEY_SIMPLEX;

const cv::Scalar WHITE(255, 255, 255), BLACK(0, 0, 0), GREY(110, 110, 110),
	LIGHT(225, 225, 225);
/* The plot's heading arrow colour, so the compass reads as the same arrow. */
const cv::Scalar HEADING_COLOR(30, 30, 210);

cv::Scalar state_color(enum mvod_run_state s)
{
	switch (s) {
	case MVOD_RUN_TRACKING: return {40, 150, 40};
	case MVOD_RUN_LOST:
	case MVOD_RUN_SOURCE_DOWN: return {30, 30, 210};
	case MVOD_RUN_STOPPING: return GREY;
	default: return {0, 140, 220}; /* STARTING, INITIALIZING: amber */
	}
}

void text(cv::Mat &img, const char *s, cv::Point org, double size, const cv::Scalar &color,
	  int thick = 1)
{
	cv::putText(img, s, org, FONT, size, color, thick, cv::LINE_AA);
}

int text_width(const char *s, double size, int thick = 1)
{
	int baseline;
	return cv::getTextSize(s, FONT, size, thick, &baseline).width;
}

/* The path as drawn: what the decimating path kept, then where the camera is now. */
std::vector<double> drawn_path(const struct mvod_view *v)
{
	const struct mvod_path &p = v->path;
	std::vector<double> xyz(p.xyz, p.xyz + 3 * p.n);
	if (v->poses && (p.n == 0 || !std::equal(v->pose.t, v->pose.t + 3, p.xyz + 3 * (p.n - 1))))
		xyz.insert(xyz.end(), v->pose.t, v->pose.t + 3);
	return xyz;
}

int draw_plot(cv::Mat &canvas, const struct mvod_view *v, const char *title)
{
	cv::Mat area = canvas(cv::Rect(0, 0, MVOD_PLOT_WIDTH, MVOD_PLOT_HEIGHT));
	struct mvod_image img = {area.cols, area.rows, (int)area.step, MVOD_PIX_BGR, area.data};
	std::vector<double> xyz = drawn_path(v);
	return mvod_plot_topdown_draw(&img, title, xyz.data(), (int)xyz.size() / 3,
				      v->poses ? v->pose.R : nullptr, nullptr, 0,
				      mvod_view_unit(v, false));
}

/* The heading again, large, as on a compass: forward (+z) up, right (+x) right. */
void draw_compass(cv::Mat &panel, const struct mvod_view *v)
{
	cv::Point c(PANEL_W / 2, CANVAS_H - MARGIN - 30 - COMPASS_R);
	cv::circle(panel, c, COMPASS_R, GREY, 1, cv::LINE_AA);
	text(panel, "+z", {c.x - 9, c.y - COMPASS_R - 6}, 0.45, GREY);
	text(panel, "+x", {c.x + COMPASS_R + 5, c.y + 5}, 0.45, GREY);
	double yaw = mvod_view_yaw_deg(v);
	char label[48];
	if (std::isnan(yaw)) {
		std::snprintf(label, sizeof(label), "heading: none");
	} else {
		double a = yaw * M_PI / 180.0, len = COMPASS_R - 8;
		cv::Point tip(c.x + (int)std::lround(len * std::sin(a)),
			      c.y - (int)std::lround(len * std::cos(a)));
		cv::arrowedLine(panel, c, tip, HEADING_COLOR, 3, cv::LINE_AA, 0, 0.25);
		std::snprintf(label, sizeof(label), "heading %+.1f deg", yaw);
	}
	text(panel, label, {(PANEL_W - text_width(label, 0.55)) / 2, CANVAS_H - MARGIN - 4}, 0.55,
	     BLACK);
}

int draw_state(cv::Mat &panel, const struct mvod_view *v, const char *banner)
{
	int y = MARGIN + 16;
	text(panel, "tracking state", {MARGIN, y}, 0.5, GREY);
	y += 36;
	/* Once mvod stopped, the state it stopped in: STOPPING alone would hide how it went. */
	bool stopped = v->state == MVOD_RUN_STOPPING;
	enum mvod_run_state shown = stopped ? v->last_state : v->state;
	text(panel, mvod_run_state_name(shown), {MARGIN, y}, 0.95, state_color(shown), 2);
	if (stopped) {
		y += 28;
		text(panel, v->tracked ? "then mvod stopped" : "then mvod stopped; it never tracked",
		     {MARGIN, y}, 0.55, v->tracked ? BLACK : state_color(MVOD_RUN_LOST));
	}
	if (banner) {
		y += 28;
		text(panel, banner, {MARGIN, y}, 0.55, BLACK);
	}
	return y + 14;
}

void draw_rows(cv::Mat &panel, const struct mvod_view *v, int64_t now_us, int y)
{
	struct mvod_view_row rows[MVOD_VIEW_MAX_ROWS];
	int n = mvod_view_rows(v, now_us, rows, MVOD_VIEW_MAX_ROWS);
	for (int i = 0; i < n; i++) {
		y += ROW_H;
		if (i % 2)
			cv::rectangle(panel, cv::Rect(MARGIN / 2, y - ROW_H + 7, PANEL_W - MARGIN,
						      ROW_H), cv::Scalar(245, 245, 245), cv::FILLED);
		text(panel, rows[i].label, {MARGIN, y}, 0.45, GREY);
		text(panel, rows[i].value, {PANEL_W - MARGIN - text_width(rows[i].value, 0.5), y}, 0.5,
		     BLACK);
	}
}

int render(const struct mvod_view *v, int64_t now_us, const struct mvod_view_labels *l,
	   cv::Mat &canvas)
{
	canvas.create(CANVAS_H, CANVAS_W, CV_8UC3);
	/* The plot paints every pixel of its part; only the panel needs a background. */
	int ret = draw_plot(canvas, v, l->title);
	if (ret)
		return ret;
	cv::Mat panel = canvas(cv::Rect(MVOD_PLOT_WIDTH, 0, PANEL_W, CANVAS_H));
	panel.setTo(WHITE);
	cv::line(panel, {0, MARGIN}, {0, CANVAS_H - MARGIN}, LIGHT, 1);
	draw_rows(panel, v, now_us, draw_state(panel, v, l->banner));
	draw_compass(panel, v);
	return 0;
}

/*
 * The window's picture, kept from one redraw to the next (ten a second): render's create()
 * allocates only when the size changes. One window, drawn from one thread.
 */
cv::Mat window_canvas;

} // namespace

extern "C" int mvod_view_write_png(const struct mvod_view *v, int64_t now_us,
				   const struct mvod_view_labels *labels, const char *path)
{
	if (!v || !labels || !path)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat canvas;
		int ret = render(v, now_us, labels, canvas);
		if (ret)
			return ret;
		mvod_image img = {canvas.cols, canvas.rows, (int)canvas.step, MVOD_PIX_BGR, canvas.data};
		return mvod_image_file_write(path, ".png", &img, 0);
	});
}

extern "C" int mvod_view_window_open(const char *name, char *err, size_t errlen)
{
	int ret = mvod_guarded([&] {
		cv::namedWindow(name, cv::WINDOW_NORMAL | cv::WINDOW_KEEPRATIO);
		cv::resizeWindow(name, CANVAS_W, CANVAS_H);
		return 0;
	});
	if (ret)
		mvod_errf(err, errlen, ret, "OpenCV cannot open a window (is highgui built with a "
					    "GUI backend?)");
	return ret;
}

extern "C" int mvod_view_window_show(const char *name, const struct mvod_view *v, int64_t now_us,
				     const struct mvod_view_labels *labels, int wait_ms, bool *quit)
{
	return mvod_guarded([&] {
		int ret = render(v, now_us, labels, window_canvas);
		if (ret)
			return ret;
		cv::imshow(name, window_canvas);
		int key = cv::waitKey(wait_ms < 1 ? 1 : wait_ms) & 0xff;
		*quit = key == 'q' || key == 27 ||
			cv::getWindowProperty(name, cv::WND_PROP_VISIBLE) < 1;
		return 0;
	});
}

extern "C" void mvod_view_window_close(const char *name)
{
	mvod_guarded([&] {
		window_canvas.release();
		cv::destroyWindow(name);
		cv::waitKey(1);
		return 0;
	});
}
