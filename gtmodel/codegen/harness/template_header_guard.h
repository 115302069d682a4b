/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The opening of every generated public header (include guard, extern "C", the shared status
 * codes) and, after the line of the split comment, its closing; gtmodel.codegen.emit.header_guard
 * splits them. Markers: @P@ the upper-case prefix, @STATUS_DEFINES@ the status codes.
 */
#ifndef @P@_H
#define @P@_H

#ifdef __cplusplus
extern "C" {
#endif

/* Status codes, shared by every gtmodel-generated library. */
#ifndef GT_STATUS_CODES
#define GT_STATUS_CODES
@STATUS_DEFINES@
#endif
/*@split*/
#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* @P@_H */
