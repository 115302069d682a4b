/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Header part of the controller of the 4 ms loop: its sample time (the Kalman, ILC and filter
 * parts follow). Markers: @M@ the C prefix in upper case, @DT@ the sample time [s].
 */
/* ---- Controller of the 4 ms loop (Dressler (2012), ch. 7) ---- */
/* Sample time of the loop [s]. */
#define @M@_CONTROLLER_DT @DT@
