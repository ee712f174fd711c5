// A plugin cannot wrap a record of its own making as a child.
use rtk_kernel::abi::ChildRef;
use rtk_kernel::Child;

fn main() {
    fn forge(r: ChildRef) -> Child {
        Child::from_counted(r)
    }
    let _ = forge;
}
