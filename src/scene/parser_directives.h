/* What each directive does to the graphics state and the scene_desc
 * (parser_directives.c; those that make entities: parser_entities.h). */
#ifndef HAZE_SCENE_PARSER_DIRECTIVES_H
#define HAZE_SCENE_PARSER_DIRECTIVES_H

#include "scene/parser_state.h"

hz_status parser_directive(parser *ps, const token *tok, hz_error *err);
/* At the end of the input `end`: what was left open, or no WorldBegin. */
hz_status parser_finish(parser *ps, file_loc end, hz_error *err);

#endif
