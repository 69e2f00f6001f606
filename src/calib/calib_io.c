/* placeholder until the module lands */
typedef int mvod_placeholder_t;
