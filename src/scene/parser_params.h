/* The scene parser's typed parameter lists (parser_params.c). */
#ifndef HAZE_SCENE_PARSER_PARAMS_H
#define HAZE_SCENE_PARSER_PARAMS_H

#include "scene/parser_state.h"

/* Reads `"type name" value...` pairs until the next directive. */
hz_status parser_params(parser *ps, param_list *out, file_loc directive, hz_error *err);

#endif
