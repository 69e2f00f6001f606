/*
 * Prints the fingerprint of each mvod LCM type: the 8 bytes (big-endian) every encoded message
 * starts with, which a subscriber's generated decoder compares with its own before decoding.
 * The build installs this output as share/mvod/lcmtypes/fingerprints.txt.
 */
#include <inttypes.h>
#include <stdio.h>

#include "mvod_pose2_t.h"
#include "mvod_pose_t.h"
#include "mvod_status2_t.h"
#include "mvod_speed_t.h"
#include "mvod_status_t.h"

static const struct {
	const char *name;
	int64_t (*hash)(void);
} types[] = {
	{"mvod.pose_t", __mvod_pose_t_get_hash},
	{"mvod.status_t", __mvod_status_t_get_hash},
	{"mvod.pose2_t", __mvod_pose2_t_get_hash},
	{"mvod.status2_t", __mvod_status2_t_get_hash},
	{"mvod.speed_t", __mvod_speed_t_get_hash},
};

int main(void)
{
	printf("# type, then its LCM fingerprint: the first 8 bytes of each message, big-endian\n");
	for (size_t i = 0; i < sizeof(types) / sizeof(types[0]); i++)
		printf("%s 0x%016" PRIx64 "\n", types[i].name, (uint64_t)types[i].hash());
	return 0;
}
