// A child is prepared and shared: the entries that change an object
// (`add_child`, `prepare`) need it exclusively, which no child gives.
use rtk_kernel::abi::ChildRef;
use rtk_kernel::Child;

fn main() {
    fn grow(c: &mut Child, other: ChildRef) {
        let _ = c.add_child(other);
    }
    let _ = grow;
}
