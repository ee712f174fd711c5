// Every entry of a record is an `unsafe extern "C" fn`: even given a record,
// safe code cannot call it.
use rtk_kernel::abi::ObjectRef;
use rtk_kernel::{Hit, Ray, TraceCtx};

fn main() {
    fn call(r: ObjectRef, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit) -> bool {
        (r.class.intersect())(r.this, ctx, ray, hit, 0)
    }
    let _ = call;
}
