/*
 * The checks of the VO's options against one another, which the option table's one-key checks
 * (config.c) cannot make; their messages name the flags.
 */
#include "mvod/config.h"

#include <errno.h>

#include "mvod/vo.h"
#include "util/errbuf.h"

int mvod_config_check_frontend(const struct mvod_vo_params *p, char *err, size_t errlen)
{
	struct mvod_vo_params d;
	mvod_vo_params_default(&d);
	const char *opt = mvod_vo_descriptor_option(p);
	if (p->mode == MVOD_VO_MAP && p->detector != MVOD_DETECTOR_ORB)
		return mvod_errf(err, errlen, -EINVAL, "--mode map keeps ORB descriptors in its map, "
				 "not %s: use --detector orb or --mode twoview",
				 mvod_detector_name(p->detector));
	if (p->frontend == MVOD_FRONTEND_KLT && opt)
		return mvod_errf(err, errlen, -EINVAL, "--%s is an option of the descriptor front "
				 "end, which --frontend klt does not run: drop --%s, or use "
				 "--frontend orb (or auto, which then picks orb)", opt, opt);
	if (mvod_vo_frontend(p) != MVOD_FRONTEND_ORB || p->max_tracks == d.max_tracks)
		return 0;
	if (p->frontend == MVOD_FRONTEND_ORB)
		return mvod_errf(err, errlen, -EINVAL, "--tracks is an option of the KLT front end, "
				 "which --frontend orb does not run: drop --tracks, or use "
				 "--frontend klt (or auto)");
	return mvod_errf(err, errlen, -EINVAL, "--tracks is an option of the KLT front end and "
			 "--%s one of the descriptor front end: drop one of them", opt);
}
