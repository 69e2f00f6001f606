/*
 * The option reference: mvod run's --help and --help-all, the option groups of mvod bench's
 * and every command's --help, and the manual page mvod(1) (mvod --man, which the build
 * installs), all from the tables the parser uses: config/config.c's keys (with their
 * defaults, ranges and config keys) and flags, and main.c's commands. None can list an option
 * the parser does not take, miss one it does, or state another default.
 */
#include "cli/cli.h"

#include <stdarg.h>
#include <string.h>

#include "mvod/capture.h"

#define WIDTH 80  /* terminal text wraps before this column */
#define COLUMN 24 /* --help's summaries start here */
#define INDENT 8  /* --help-all's descriptions */

/* The reference's groups, in order: a config section's keys, then the flags of that group. */
static const struct group {
	const char *title, *section;
} groups[] = {
	{"Input", "source"}, {"Calibration", "calibration"}, {"Visual odometry", "vo"},
	{"LCM", "lcm"},      {"Output", "output"},           {"Configuration", NULL},
	{"Cameras", NULL},   {"General", "log"},
};
#define NGROUPS (sizeof(groups) / sizeof(groups[0]))

/* A key of the table or a flag, as the reference shows it. */
struct entry {
	char short_flag;
	const char *flag, *arg, *summary, *help;
	const char *const *choices; /* the value's name when arg is NULL */
	int key;                    /* index into mvod_config_keys, or -1 for a flag */
};

const struct cli_command cli_commands[CLI_CMD_COUNT] = {
	[CLI_CMD_RUN] = {"run", "--source URI [options]",
			 "track a source and publish poses (the default command)"},
	[CLI_CMD_CALIBRATE] = {"calibrate", "--source URI --board SPEC --out calib.json [options]",
			       "calibrate a camera from a ChArUco or chessboard recording"},
	[CLI_CMD_MOUNT] = {"mount", "--source URI --board SPEC --calib FILE [options]",
			   "the camera's height, pitch and roll from a board on the floor"},
	[CLI_CMD_BOARD] = {"board", "--board SPEC --out board.png [--dpi N]",
			   "write a printable calibration target"},
	[CLI_CMD_CONVERT] = {"calib-convert", "IN OUT [--to mvod|opencv|ros|kitti|dso] [--size WxH]",
			     "convert a calibration file between mvod JSON, OpenCV, ROS, KITTI and DSO"},
	[CLI_CMD_BENCH] = {"bench", "--source URI [--gt FILE] [options] [--sweep [GRID]]",
			   "measure accuracy and speed against ground truth"},
	[CLI_CMD_VIEW] = {"view", "[--lcm-url URL] [--png FILE [--every N]] [options]",
			  "draw the path, heading, state and rates of a running mvod or of its LCM log"},
	[CLI_CMD_SPEED_LOG] = {"speed-log", "GT OUT.lcmlog [--times FILE] [options]",
			       "an LCM log of the speed along a ground truth, for --scale external"},
};

/* What the texts share: mvod run's synopsis after its first line, its purpose, and more. */
static const char *const run_synopsis[] = {"[run] --config FILE [options]", "--list-cameras",
					   NULL};
static const char purpose[] =
	"Monocular visual odometry: frames in, camera poses out over LCM and to files.";
static const char about[] =
	"mvod reads frames from one camera (V4L2, libcamera), a video, an image folder or a "
	"dataset (KITTI, EuRoC, TUM), estimates the camera's motion by monocular visual "
	"odometry (KLT tracks or ORB/SIFT features, a local map refined by bundle adjustment), "
	"and publishes one pose per frame over LCM (mvod.pose2_t on MVOD_POSE2 and the v1 "
	"mvod.pose_t on MVOD_POSE; status on MVOD_STATUS2 and MVOD_STATUS), to a trajectory file "
	"and to a plot. Its other commands calibrate a camera, measure its mount, and measure "
	"mvod against ground truth.";
static const char signals[] =
	"SIGTERM or SIGINT stop cleanly: the frame in hand is finished, the outputs closed, a last "
	"status published (a second one stops at once). SIGHUP reopens the trajectory file and a "
	"file:// LCM log by name (log rotation).";
static const char exit_status[] =
	"0 on success; 1 on a run-time fault, which a restart may fix (a camera absent, a write "
	"that failed, a source that broke off); 2 on a usage or configuration error, which only "
	"an edit fixes (a bad flag or config file; a calibration, ground truth or speed source "
	"that cannot serve; an output refused at start). The service does not restart on 2. "
	"Every command exits by the same causes; its --help says which are its own.";
static const char config_file[] =
	"mvod --config FILE reads an INI file: a [section] line, then key = value lines; # or ; "
	"starts a comment line, and \" ;\" a comment after a value. Each option above that names "
	"a config key is one; flags given with --config override the file. mvod --print-config "
	"writes the settings in effect as such a file.";
/* Command lines; a newline goes on with the next line (" \\" before it, as in a shell). */
static const char *const examples[] = {
	"mvod --source 'v4l2:/dev/video0?width=640&height=480&fps=30' --calib cam.json",
	"mvod --source file:video.mkv --calib calib.json --lcm-url memq://\n"
	"--trajectory out.tum --plot out.png",
	"mvod --source kitti:seq/06 --gt poses/06.txt --scale gt --trajectory out.kitti",
	"mvod --config /etc/mvod/mvod.conf --print-config",
	"mvod calibrate --source file:board.mkv --out calib.json\n"
	"--board charuco:5x7:0.04:0.02:DICT_6X6_250",
	NULL,
};
/* A name and what it is: mvod(1)'s ENVIRONMENT and FILES. */
static const struct item {
	const char *name, *text;
} environment[] = {
	{"LCM_DEFAULT_URL", "the LCM provider when --lcm-url is not given"},
	{"JOURNAL_STREAM", "set by systemd: log lines then carry the journal's priorities"},
	{"LIBCAMERA_LOG_LEVELS, OPENCV_FFMPEG_LOGLEVEL",
	 "the libraries' own logs: errors only, unless --log-level debug or set"},
	{NULL, NULL},
}, files[] = {
	{"/etc/mvod/mvod.conf", "the service's configuration: mvod.service runs mvod run --config "
				"/etc/mvod/mvod.conf, mvod@NAME.service reads /etc/mvod/NAME.conf"},
	{MVOD_DATADIR "/mvod/mvod.conf.example", "every key with its default and meaning"},
	{"/var/lib/mvod", "the one folder the service may write to"},
	{MVOD_PREFIX "/lib/systemd/system/mvod.service, mvod@.service", "the systemd units"},
	{MVOD_DATADIR "/mvod/lcmtypes/*.lcm", "the LCM types, for lcm-gen in other languages"},
	{NULL, NULL},
};
static const char see_also[] =
	"mvod COMMAND --help for each command's options; mvod-synth --help; lcm-logplayer(1), "
	"lcm-spy(1), systemctl(1), journalctl(1).";

static bool key_in(const struct mvod_config_key *k, enum cli_scope s)
{
	if (s == CLI_SCOPE_GENERAL)
		return strcmp(k->section, "log") == 0;
	return s == CLI_SCOPE_RUN || !k->run_only;
}

static bool flag_in(const struct mvod_config_flag *f, enum cli_scope s)
{
	return f->every_command || s == CLI_SCOPE_RUN;
}

static struct entry key_entry(int k)
{
	const struct mvod_config_key *c = &mvod_config_keys[k];
	return (struct entry){c->short_flag, c->flag, c->arg, c->summary, c->help,
			      c->type == MVOD_CONFIG_ENUM ? c->choices : NULL, k};
}

static struct entry flag_entry(int f)
{
	const struct mvod_config_flag *c = &mvod_config_flags[f];
	return (struct entry){c->short_flag, c->flag, c->arg, c->summary, c->help, NULL, -1};
}

/* Appends to buf (len bytes, *n used), never past its end. */
__attribute__((format(printf, 4, 5))) static void add(char *buf, size_t len, size_t *n,
						       const char *fmt, ...)
{
	if (*n >= len)
		return;
	va_list ap;
	va_start(ap, fmt);
	int w = vsnprintf(buf + *n, len - *n, fmt, ap);
	va_end(ap);
	*n += w > 0 ? (size_t)w : 0;
}

/* The value's name: "N", "twoview|map", or "" for a flag that takes none. */
static void value_name(const struct entry *e, char *buf, size_t len)
{
	size_t n = 0;
	buf[0] = '\0';
	if (e->arg)
		add(buf, len, &n, "%s", e->arg);
	for (int i = 0; !e->arg && e->choices && e->choices[i]; i++)
		add(buf, len, &n, "%s%s", i ? "|" : "", e->choices[i]);
}

/* "-q, --quiet", "--features N", "--mode twoview|map". */
static void head(const struct entry *e, char *buf, size_t len)
{
	size_t n = 0;
	char value[128];
	value_name(e, value, sizeof(value));
	buf[0] = '\0';
	if (e->short_flag)
		add(buf, len, &n, "-%c, ", e->short_flag);
	add(buf, len, &n, "--%s%s%s", e->flag, *value ? " " : "", value);
}

/* The summary, then the rest: "ORB's or SIFT's feature count per frame. Picks ..." */
static void describe(const struct entry *e, char *buf, size_t len)
{
	size_t n = 0;
	add(buf, len, &n, "%s.%s%s", e->summary, e->help ? " " : "", e->help ? e->help : "");
}

/*
 * What a key's value is when not given, what it takes and where the config file sets it:
 * "Default: 2000; 50 to 100000. Config: [vo] features." A flag: "" (no setting).
 */
static void facts(const struct entry *e, char *buf, size_t len)
{
	size_t n = 0;
	buf[0] = '\0';
	if (e->key < 0)
		return;
	const struct mvod_config_key *k = &mvod_config_keys[e->key];
	struct mvod_config d;
	mvod_config_default(&d);
	char value[256];
	mvod_config_value_text(&d, e->key, value, sizeof(value));
	if (k->type == MVOD_CONFIG_BOOL) {
		add(buf, len, &n, "Config: [%s] %s = %s (default %s).", k->section, k->key,
		    k->flag_value ? "true" : "false", value);
		return;
	}
	add(buf, len, &n, "Default: %s", k->dflt ? k->dflt : *value ? value : "none");
	if (k->type == MVOD_CONFIG_DOUBLE)
		add(buf, len, &n, "; %g to %g", k->lo, k->hi);
	else if (k->type == MVOD_CONFIG_INT || k->type == MVOD_CONFIG_INT64)
		add(buf, len, &n, "; %.0f to %.0f%s", k->lo, k->hi, k->odd ? ", odd, or 0" : "");
	else if (k->type == MVOD_CONFIG_STRING && k->hi > 0)
		add(buf, len, &n, "; at most %.0f characters", k->hi);
	add(buf, len, &n, ". Config: [%s] %s.", k->section, k->key);
}

/* text from column col (what the line holds already), wrapped at WIDTH at indent; ends it. */
static void wrap(FILE *out, const char *text, int col, int indent)
{
	for (const char *p = text; *p;) {
		int w = (int)strcspn(p, " ");
		if (col > indent && col + 1 + w >= WIDTH) {
			fprintf(out, "\n%*s", indent, "");
			col = indent;
		} else if (col > indent) {
			fputc(' ', out);
			col++;
		}
		fprintf(out, "%.*s", w, p);
		col += w;
		p += w;
		while (*p == ' ')
			p++;
	}
	fputc('\n', out);
}

/*
 * Calls entry for each option of scope, group by group, title(group) before a group's first
 * and title(NULL) after its last; groups without one are left out.
 */
static void each_entry(FILE *out, enum cli_scope s, void (*title)(FILE *, const char *),
		       void (*entry)(FILE *, const struct entry *))
{
	for (size_t g = 0; g < NGROUPS; g++) {
		bool titled = false;
		for (int k = 0; k < mvod_config_nkeys; k++) {
			const struct mvod_config_key *c = &mvod_config_keys[k];
			if (!groups[g].section || strcmp(c->section, groups[g].section) ||
			    !key_in(c, s))
				continue;
			if (!titled)
				title(out, groups[g].title);
			titled = true;
			struct entry e = key_entry(k);
			entry(out, &e);
		}
		for (int f = 0; f < MVOD_FLAG_COUNT; f++) {
			const struct mvod_config_flag *c = &mvod_config_flags[f];
			if (strcmp(c->group, groups[g].title) || !flag_in(c, s))
				continue;
			if (!titled)
				title(out, groups[g].title);
			titled = true;
			struct entry e = flag_entry(f);
			entry(out, &e);
		}
		if (titled)
			title(out, NULL);
	}
}

/* --- the terminal --- */

static void text_title(FILE *out, const char *title)
{
	fprintf(out, title ? "%s:\n" : "\n", title);
}

/* "where frames come from (required): file:, images:, ...": the scheme table's schemes. */
static void source_summary(const struct entry *e, char *buf, size_t len)
{
	size_t n = 0;
	add(buf, len, &n, "%s", e->summary);
	for (int i = 0; mvod_source_backends[i]; i++)
		add(buf, len, &n, "%s%s:", i ? ", " : ": ", mvod_source_backends[i]->scheme);
}

static bool is_source(const struct entry *e)
{
	return strcmp(e->flag, "source") == 0;
}

/* --help: "  --flag ARG" and the summary from COLUMN, or on the next line when it is wider. */
static void short_entry(FILE *out, const struct entry *e)
{
	char h[128], text[512];
	head(e, h, sizeof(h));
	int col = fprintf(out, "  %s", h);
	if (col < COLUMN - 1)
		col += fprintf(out, "%*s", COLUMN - col, "");
	else
		col = fprintf(out, "\n%*s", COLUMN, "") - 1;
	if (is_source(e))
		source_summary(e, text, sizeof(text));
	wrap(out, is_source(e) ? text : e->summary, col, COLUMN);
}

/* --help-all: the head on a line, then the description, the sources' forms and the facts. */
static void full_entry(FILE *out, const struct entry *e)
{
	char h[128], text[2048];
	head(e, h, sizeof(h));
	fprintf(out, "  %s\n%*s", h, INDENT, "");
	describe(e, text, sizeof(text));
	wrap(out, text, INDENT, INDENT);
	for (int i = 0; is_source(e) && mvod_source_backends[i]; i++) {
		fprintf(out, "%*s", INDENT + 2, "");
		wrap(out, mvod_source_backends[i]->summary, INDENT + 2, INDENT + 4);
	}
	facts(e, text, sizeof(text));
	if (text[0]) {
		fprintf(out, "%*s", INDENT, "");
		wrap(out, text, INDENT, INDENT);
	}
}

void cli_usage_options(FILE *out, enum cli_scope scope)
{
	each_entry(out, scope, text_title, short_entry);
}

void cli_usage_general(FILE *out)
{
	cli_usage_options(out, CLI_SCOPE_GENERAL);
}

void cli_usage_synopsis(FILE *out, const char *command)
{
	for (const struct cli_command *c = cli_commands; c < cli_commands + CLI_CMD_COUNT; c++)
		if (strcmp(c->name, command) == 0)
			fprintf(out, "Usage: mvod %s%s %s\n", strcmp(command, "run") ? "" : "[",
				strcmp(command, "run") ? c->name : "run]", c->args);
}

/* mvod run's synopsis, its other forms, the other commands', and text (its purpose). */
static void run_header(FILE *out, const char *text)
{
	cli_usage_synopsis(out, "run");
	for (int i = 0; run_synopsis[i]; i++)
		fprintf(out, "       mvod %s\n", run_synopsis[i]);
	fprintf(out, "       mvod COMMAND ...   (mvod COMMAND --help)\n\n");
	wrap(out, text, 0, 0);
	fputc('\n', out);
}

/* A command line, its newlines written as cont ("  mvod ...", then cont before each next). */
static void example(FILE *out, const char *text, const char *cont)
{
	fputs("  ", out);
	for (const char *p = text; *p; p++)
		if (*p == '\n')
			fputs(cont, out);
		else
			fputc(*p, out);
	fputc('\n', out);
}

/* Commands, signals, examples, exit status: what follows the options in --help. */
static void run_footer(FILE *out)
{
	fprintf(out, "Commands:\n");
	for (const struct cli_command *c = cli_commands; c < cli_commands + CLI_CMD_COUNT; c++) {
		int col = fprintf(out, "  %s", c->name);
		col += fprintf(out, "%*s", COLUMN - col, "");
		wrap(out, c->purpose, col, COLUMN);
	}
	fprintf(out, "\nSignals:");
	wrap(out, signals, 8, 0);
	fprintf(out, "\nExamples:\n");
	for (int i = 0; examples[i]; i++)
		example(out, examples[i], " \\\n       ");
	fprintf(out, "\nExit status:");
	wrap(out, exit_status, 12, 0);
}

void cli_usage_run(FILE *out)
{
	run_header(out, purpose);
	cli_usage_options(out, CLI_SCOPE_RUN);
	run_footer(out);
	fputc('\n', out);
	wrap(out, "mvod --help-all describes every option: its value, default and config key; "
		  "man mvod is the manual.", 0, 0);
}

void cli_help_all(FILE *out)
{
	run_header(out, about);
	each_entry(out, CLI_SCOPE_RUN, text_title, full_entry);
	fprintf(out, "Configuration file:");
	wrap(out, config_file, 19, 0);
	fputc('\n', out);
	run_footer(out);
}

/* --- mvod(1) --- */

/*
 * text for roff: backslashes and hyphens escaped, a leading dot or quote made text, and a
 * place to break a line after a URI's ? and & (a v4l2: URI is wider than a terminal).
 */
static void roff(FILE *out, const char *text)
{
	if (*text == '.' || *text == '\'')
		fputs("\\&", out);
	for (const char *p = text; *p; p++) {
		if (*p == '\\')
			fputs("\\e", out);
		else if (*p == '-')
			fputs("\\-", out);
		else
			fputc(*p, out);
		if (*p == '?' || *p == '&')
			fputs("\\:", out);
	}
}

/* A section with one paragraph of text. */
static void man_section(FILE *out, const char *name, const char *text)
{
	fprintf(out, ".SH %s\n", name);
	roff(out, text);
	fputc('\n', out);
}

static void man_title(FILE *out, const char *title)
{
	if (title)
		fprintf(out, ".SS %s\n", title);
}

/* ".TP", the option in bold and its value in italics, the description, the facts. */
static void man_entry(FILE *out, const struct entry *e)
{
	char text[2048];
	fputs(".TP\n", out);
	if (e->short_flag)
		fprintf(out, "\\fB\\-%c\\fR, ", e->short_flag);
	fputs("\\fB\\-\\-", out);
	roff(out, e->flag);
	fputs("\\fR", out);
	value_name(e, text, sizeof(text));
	if (text[0]) {
		fputs(" \\fI", out);
		roff(out, text);
		fputs("\\fR", out);
	}
	fputc('\n', out);
	describe(e, text, sizeof(text));
	roff(out, text);
	fputc('\n', out);
	for (int i = 0; is_source(e) && mvod_source_backends[i]; i++) {
		fputs(".br\n", out);
		roff(out, mvod_source_backends[i]->summary);
		fputc('\n', out);
	}
	facts(e, text, sizeof(text));
	if (text[0]) {
		fputs(".br\n", out);
		roff(out, text);
		fputc('\n', out);
	}
}

static void man_synopsis(FILE *out)
{
	fputs(".SH SYNOPSIS\n.nf\n", out);
	for (const struct cli_command *c = cli_commands; c < cli_commands + CLI_CMD_COUNT; c++) {
		bool run = strcmp(c->name, "run") == 0;
		fprintf(out, "\\fBmvod\\fR %s%s%s ", run ? "[\\fB" : "\\fB", c->name,
			run ? "\\fR]" : "\\fR");
		roff(out, c->args);
		fputc('\n', out);
		for (int i = 0; run && run_synopsis[i]; i++) {
			fputs("\\fBmvod\\fR ", out);
			roff(out, run_synopsis[i]);
			fputc('\n', out);
		}
	}
	fputs(".fi\n", out);
}

/* Which of the options mvod bench takes too: all but mvod run's alone (run_only, its flags). */
static void man_options_intro(FILE *out)
{
	char text[1024];
	size_t n = 0;
	add(text, sizeof(text), &n, "The options of mvod run, by group. mvod bench takes the same "
				    "but");
	for (int k = 0, i = 0; k < mvod_config_nkeys; k++)
		if (!key_in(&mvod_config_keys[k], CLI_SCOPE_BENCH))
			add(text, sizeof(text), &n, "%s --%s", i++ ? "," : "", mvod_config_keys[k].flag);
	for (int f = 0; f < MVOD_FLAG_COUNT; f++)
		if (!flag_in(&mvod_config_flags[f], CLI_SCOPE_BENCH))
			add(text, sizeof(text), &n, ", --%s", mvod_config_flags[f].flag);
	add(text, sizeof(text), &n, " (mvod bench --help).");
	man_section(out, "OPTIONS", text);
}

static void man_commands(FILE *out)
{
	fputs(".SH COMMANDS\n", out);
	for (const struct cli_command *c = cli_commands; c < cli_commands + CLI_CMD_COUNT; c++) {
		fprintf(out, ".TP\n\\fB%s\\fR\n", c->name);
		roff(out, c->purpose);
		if (strcmp(c->name, "run") == 0)
			fputs(": its options follow.\n", out);
		else
			fprintf(out, ". Its options: \\fBmvod %s \\-\\-help\\fR.\n", c->name);
	}
}

static void man_items(FILE *out, const char *section, const struct item *items)
{
	fprintf(out, ".SH %s\n", section);
	for (const struct item *i = items; i->name; i++) {
		fputs(".TP\n\\fB", out);
		roff(out, i->name);
		fputs("\\fR\n", out);
		roff(out, i->text);
		fputs(".\n", out);
	}
}

static void man_examples(FILE *out)
{
	fputs(".SH EXAMPLES\n.nf\n", out);
	for (int i = 0; examples[i]; i++) {
		for (const char *p = examples[i]; *p;) {
			size_t n = strcspn(p, "\n");
			char line[256];
			snprintf(line, sizeof(line), "%s%.*s", p == examples[i] ? "" : "     ", (int)n,
				 p);
			roff(out, line);
			fputs(p[n] ? " \\e\n" : "\n", out);
			p += n + (p[n] != '\0');
		}
	}
	fputs(".fi\n", out);
}

void cli_man(FILE *out)
{
	fprintf(out, ".\\\" mvod(1), generated by mvod --man from its option table: do not edit.\n"
		     ".TH MVOD 1 \"\" \"mvod %s\" \"User Commands\"\n"
		     ".\\\" Left-aligned and unhyphenated: options, URIs and paths stay whole.\n"
		     ".ad l\n.nh\n"
		     ".SH NAME\nmvod \\- monocular visual odometry daemon: one camera in, poses "
		     "out over LCM\n", MVOD_VERSION);
	man_synopsis(out);
	man_section(out, "DESCRIPTION", about);
	man_commands(out);
	man_options_intro(out);
	each_entry(out, CLI_SCOPE_RUN, man_title, man_entry);
	man_section(out, "CONFIGURATION FILE", config_file);
	man_section(out, "SIGNALS", signals);
	man_section(out, "EXIT STATUS", exit_status);
	man_items(out, "ENVIRONMENT", environment);
	man_items(out, "FILES", files);
	man_examples(out);
	man_section(out, "SEE ALSO", see_also);
}
