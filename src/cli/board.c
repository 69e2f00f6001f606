/* mvod board: a printable calibration target at its true physical size. */
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/board.h"
#include "mvod/log.h"
#include "util/image_file.h"

#define MM_PER_INCH 25.4
/* Below this a printed marker's cells blur into each other, and a square's edge is jagged. */
#define MIN_PX_PER_SQUARE 20
/* 40 000 px at 300 dpi is a 3.4 m poster: anything larger is a typo in the spec. */
#define MAX_SIDE_PX 40000

static void usage(FILE *out)
{
	cli_usage_synopsis(out, "board");
	fprintf(out,
"Writes a printable calibration target at its exact physical size: each square is\n"
"SQUARE_M metres when printed at 100 %% (the PNG records its DPI), inside a white border\n"
"of one square, which names the spec at the bottom. Says which paper it needs, leaving the\n"
"6.35 mm (1/4 inch) margins most printers cannot print in.\n"
"\n"
"  --board SPEC          charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT (COLSxROWS squares) or\n"
"                        chessboard:COLSxROWS:SQUARE_M (inner corners) (required)\n"
"  --out FILE.png        image to write (required)\n"
"  --dpi N               printer resolution, 50..2400 (default 300)\n"
"\n");
	cli_usage_general(out);
	fprintf(out,
"Print at 100 %% (\"actual size\", no \"fit to page\"), glue the sheet flat on something\n"
"rigid, measure a square with a ruler, and give the measured size to mvod calibrate.\n"
"\n"
"Example:\n"
"  mvod board --board charuco:5x7:0.04:0.02:DICT_6X6_250 --out board.png --dpi 300\n"
"\n"
"Exit status: 0 on success, 1 on a run-time fault, 2 on a usage error (--out refused at\n"
"start too).\n");
}

enum board_opt_id { OPT_BOARD = CLI_OPT_OWN, OPT_OUT, OPT_DPI };

static const struct option own_opts[] = {
	{"board", required_argument, NULL, OPT_BOARD},
	{"out", required_argument, NULL, OPT_OUT},
	{"dpi", required_argument, NULL, OPT_DPI},
	{NULL, 0, NULL, 0},
};

struct cli {
	struct mvod_board board;
	const char *out;
	double dpi;
	int have_board, quiet;
};

static int parse_own(int id, const char *arg, void *ctx)
{
	struct cli *c = ctx;
	switch (id) {
	case OPT_BOARD: c->have_board = 1; return cli_parse_board(arg, &c->board);
	case OPT_OUT: c->out = arg; return 0;
	case OPT_DPI: return cli_parse_double("dpi", arg, 50, 2400, &c->dpi);
	}
	return -ENOENT;
}

/*
 * What printers cannot print at each edge of the sheet: 6.35 mm (a quarter inch) is the
 * margin most office laser and inkjet printers need; a board wider than the sheet less two of
 * them loses its edge, or gets shrunk by the driver.
 */
#define PRINTER_MARGIN_MM 6.35

/*
 * Names in buf the smallest standard sheet whose printable area (PRINTER_MARGIN_MM in from
 * every edge) the w x h mm image fits in; false when none.
 */
static bool paper_for(double w, double h, char *buf, size_t len)
{
	static const struct {
		const char *name;
		double w, h;
	} papers[] = {{"A4", 210, 297}, {"Letter", 215.9, 279.4}, {"A3", 297, 420}, {"A2", 420, 594}};
	w += 2 * PRINTER_MARGIN_MM;
	h += 2 * PRINTER_MARGIN_MM;
	for (size_t i = 0; i < sizeof(papers) / sizeof(papers[0]); i++) {
		bool portrait = w <= papers[i].w && h <= papers[i].h;
		if (portrait || (h <= papers[i].w && w <= papers[i].h)) {
			snprintf(buf, len, "%s (%s)", papers[i].name, portrait ? "portrait" : "landscape");
			return true;
		}
	}
	return false;
}

static void print_advice(const struct cli *c, const struct mvod_image *img, int pps)
{
	double mm_per_px = MM_PER_INCH / c->dpi, square_mm = pps * mm_per_px;
	double w = img->w * mm_per_px, h = img->h * mm_per_px;
	char paper[32];
	printf("%s: wrote %s: %d x %d px at %g dpi = %.1f x %.1f mm, squares of %.2f mm\n", cli_prog,
	       c->out, img->w, img->h, c->dpi, w, h, square_mm);
	if (paper_for(w, h, paper, sizeof(paper)))
		printf("%s: print it on %s, whose %.2f mm printer margins it clears,", cli_prog, paper,
		       PRINTER_MARGIN_MM);
	else
		printf("%s: it needs a sheet of at least %.0f x %.0f mm with the printer's margins "
		       "(larger than A2); print it", cli_prog, w + 2 * PRINTER_MARGIN_MM,
		       h + 2 * PRINTER_MARGIN_MM);
	printf(" at 100 %% (\"actual size\", no scaling, not \"fit to page\"), and glue it flat on "
	       "something rigid\n");
	const struct mvod_board *b = &c->board;
	printf("%s: measure a square with a ruler (it should be %.2f mm) and give mvod calibrate the "
	       "measured size in metres:\n  --board ", cli_prog, square_mm);
	if (b->kind == MVOD_BOARD_CHARUCO)
		printf("charuco:%dx%d:SQUARE_M:MARKER_M:%s (a marker should be %.1f mm)\n", b->cols,
		       b->rows, b->dict_name, square_mm * b->marker_m / b->square_m);
	else
		printf("chessboard:%dx%d:SQUARE_M\n", b->cols, b->rows);
}

static int write_board(const struct cli *c)
{
	int across, down;
	mvod_board_squares(&c->board, &across, &down);
	int pps = (int)lround(c->board.square_m * c->dpi / (MM_PER_INCH / 1000));
	if (pps < MIN_PX_PER_SQUARE || (long)pps * (across + 2) > MAX_SIDE_PX ||
	    (long)pps * (down + 2) > MAX_SIDE_PX) {
		LOG(ERROR, "at %g dpi a %g m square is %d px: choose a --dpi that makes it %d to %d px",
		    c->dpi, c->board.square_m, pps, MIN_PX_PER_SQUARE,
		    MAX_SIDE_PX / (across > down ? across + 2 : down + 2));
		return -EINVAL;
	}
	struct mvod_image img;
	char caption[256], spec[128];
	mvod_board_format(&c->board, spec, sizeof(spec));
	snprintf(caption, sizeof(caption), "mvod board  %s  squares %.2f mm at 100 %%", spec,
		 pps * MM_PER_INCH / c->dpi);
	int ret = mvod_board_draw(&c->board, pps, pps, &img);
	if (!ret)
		ret = mvod_board_caption(&img, pps, caption);
	if (!ret)
		ret = mvod_image_file_write(c->out, ".png", &img, c->dpi);
	if (ret)
		LOG(ERROR, "cannot write %s: %s", c->out, strerror(-ret));
	else if (!c->quiet)
		print_advice(c, &img, pps);
	mvod_board_image_free(&img);
	return ret;
}

int mvod_cmd_board(int argc, char **argv)
{
	struct cli c = {.dpi = 300};
	int ret = cli_getopt(argc, argv, own_opts, parse_own, &c, usage, NULL, &c.quiet);
	if (ret)
		return ret > 0 ? 0 : EXIT_USAGE;
	if (!c.have_board || !c.out) {
		fprintf(stderr, "%s: %s is required; see %s --help\n", cli_prog,
			c.have_board ? "--out FILE.png" : "--board SPEC", cli_prog);
		return EXIT_USAGE;
	}
	if (cli_check_writable("--out", c.out))
		return EXIT_USAGE;
	return write_board(&c) ? EXIT_FAILURE : EXIT_SUCCESS;
}
