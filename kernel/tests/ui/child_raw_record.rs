// An aggregate holds its children as `Child`: it has no accessor for the
// raw record or the object pointer, and its fields are private.
fn main() {
    fn grab(c: &rtk_kernel::Child) {
        let _record = c.object_ref();
        let _fields = c.obj;
    }
    let _ = grab;
}
