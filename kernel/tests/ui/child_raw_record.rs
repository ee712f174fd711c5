// An aggregate may read its child's record, but not call it: every entry is
// an `unsafe extern "C" fn`, and plugin crates forbid `unsafe`.
#![forbid(unsafe_code)]
use rtk_kernel::{Child, Hit, Ray, TraceCtx};

fn main() {
    fn call(c: &Child, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit) -> bool {
        unsafe { (c.raw_class().intersect())(c.raw_this(), ctx, ray, hit, 0) }
    }
    let _ = call;
}
