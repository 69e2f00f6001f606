#include "mvod/sink.h"

bool mvod_faults_set(struct mvod_faults *f, int32_t bit)
{
	bool first = !(f->bits & bit);
	f->bits |= bit;
	f->status_due |= first;
	return first;
}
