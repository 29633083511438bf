/* The scene parser's directives that create entities or change what later
 * entities get: materials, media, area lights, objects (parser_entities.c). */
#ifndef HAZE_SCENE_PARSER_ENTITIES_H
#define HAZE_SCENE_PARSER_ENTITIES_H

#include <stdbool.h>

#include "scene/parser_state.h"

/* *handled is false when `d` is none of them. */
hz_status parser_entity_directive(parser *ps, const token *d, bool *handled, hz_error *err);
/* After a defining directive failed (ps->defining): an entity of that name
 * with no parameters (a constant texture, a diffuse material, a homogeneous
 * medium) unless one exists. Such a scene is reported, never rendered. */
void parser_define_stand_in(parser *ps);
/* After the parse: one error per NamedMaterial no MakeNamedMaterial defined. */
void parser_report_pending_materials(const parser *ps, hz_errors *errs);

#endif
