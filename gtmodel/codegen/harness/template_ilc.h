/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Header part of the learned ILC correction. Markers: @M@ the C prefix in upper case,
 * @LENGTH@ the cycles of the table, @D@ the size of the correction.
 */
/* Cycles of the learned ILC table (k = 0 .. ILC_LENGTH - 1) and size of the correction. */
#define @M@_ILC_LENGTH @LENGTH@
#define @M@_ILC_D @D@

