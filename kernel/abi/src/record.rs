//! The generator of the records: one `#[repr(C)]` abi_stable prefix type per
//! declaration of [`crate::entries`].
//!
//! Why a muncher: abi_stable's derive reads a function pointer's layout from
//! the field's own tokens, so every field type must be written out before
//! the struct is (no macro may stand in a field's type). The generator walks
//! the entries one at a time, accumulating fields, and emits the struct at
//! the end; the other generators (`rtk_sdk::__shims!`, `rtk_sdk::__callers!`)
//! emit one item per entry and need no walk.

/// Write a record from its declaration (see [`crate::entries`]).
#[doc(hidden)]
#[macro_export]
macro_rules! __record {
    // ---- entry: flatten the sections into groups tagged with how their
    // ---- fields are typed (bare, optional, flag, appended).
    (config [$($cfg:tt)*]
     kind $kind:ident, module $module:ident, prefix $prefix:ident, trait $trait_:ident;
     entries { $($e:tt)* }
     caps { $( $(#[$cm:meta])* $cap:ident { $($ce:tt)* } )* }
     flags { $( $(#[$fm:meta])* $fcap:ident $flag:ident ; )* }
     appended { $($a:tt)* }
     appended_caps { $( $(#[$acm:meta])* $acap:ident { $($ace:tt)* } )* }
    ) => {
        $crate::__record!(@munch [$kind $module $prefix] []
            bare { $($e)* }
            $( opt { $($ce)* } )*
            flag { $( $(#[$fm])* $flag ; )* }
            last {}
            app { $($a)* }
            $( app { $($ace)* } )*
        );
    };

    // ---- one entry: its raw function type by calling convention
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* hot $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> plain [$($ret:tt)*] = $fb:expr ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void, ctx: *mut $crate::TraceCtx $(, $($arg)*)*) -> $($ret)*]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* hot $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> unit [] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void, ctx: *mut $crate::TraceCtx $(, $($arg)*)*)]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* hot $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> option [$($ret:tt)*] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void, ctx: *mut $crate::TraceCtx $(, $($arg)*)*, out: *mut $($ret)*) -> bool]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* pure $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> plain [$($ret:tt)*] = $fb:expr ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void $(, $($arg)*)*) -> $($ret)*]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* pure $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> option [$($ret:tt)*] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void $(, $($arg)*)*, out: *mut $($ret)*) -> bool]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* cold $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> status [] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void $(, $($arg)*)*, sink: $crate::ErrSink) -> i32]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* cold $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> unit [] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void $(, $($arg)*)*, sink: $crate::ErrSink) -> i32]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* cold $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> value [$($ret:tt)*] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void $(, $($arg)*)*, out: *mut $($ret)*, sink: $crate::ErrSink) -> i32]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* cold $name:ident ( $recv:tt $(, ($($arg:tt)*))* ) -> result [$($ret:tt)*] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn(this: *$recv ::std::ffi::c_void $(, $($arg)*)*, out: *mut $($ret)*, sink: $crate::ErrSink) -> i32]
            $mode { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {
        $(#[$m:meta])* ctor $name:ident ( new $(, ($($arg:tt)*))* ) -> status [] ;
        $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@push $hdr [$($acc)*] $mode [$(#[$m])*] $name
            [unsafe extern "C" fn($($($arg)*,)* env: *const $crate::CreateEnv, sink: $crate::ErrSink) -> *mut ::std::ffi::c_void]
            $mode { $($rest)* } $($more)*);
    };
    // ---- flags, the end of the prefix, empty groups
    (@munch $hdr:tt [$($acc:tt)*] flag { $(#[$m:meta])* $flag:ident ; $($rest:tt)* } $($more:tt)*) => {
        $crate::__record!(@munch $hdr [$($acc)* $(#[$m])* pub $flag: bool,] flag { $($rest)* } $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] last {} $($more:tt)*) => {
        $crate::__record!(@munch $hdr [$($acc)*
            /// The minor version of `rtk-abi` the record was built against:
            /// the end of the stable prefix; every field after it may be
            /// absent from an older plugin and is read as `None`.
            #[sabi(last_prefix_field)]
            pub abi_minor: u32,
        ] $($more)*);
    };
    (@munch $hdr:tt [$($acc:tt)*] $mode:ident {} $($more:tt)*) => {
        $crate::__record!(@munch $hdr [$($acc)*] $($more)*);
    };

    // ---- how a field is typed in its section
    (@push $hdr:tt [$($acc:tt)*] bare [$($d:tt)*] $name:ident [$($ty:tt)*] $($tail:tt)*) => {
        $crate::__record!(@munch $hdr [$($acc)* $($d)* pub $name: $($ty)*,] $($tail)*);
    };
    (@push $hdr:tt [$($acc:tt)*] opt [$($d:tt)*] $name:ident [$($ty:tt)*] $($tail:tt)*) => {
        $crate::__record!(@munch $hdr [$($acc)* $($d)* pub $name: Option<$($ty)*>,] $($tail)*);
    };
    (@push $hdr:tt [$($acc:tt)*] app [$($d:tt)*] $name:ident [$($ty:tt)*] $($tail:tt)*) => {
        $crate::__record!(@munch $hdr [$($acc)* $($d)* #[sabi(missing_field(default))] pub $name: Option<$($ty)*>,] $($tail)*);
    };

    // ---- the record
    (@munch [Services $module:ident $prefix:ident] [$($acc:tt)*]) => {
        /// The scene services record, generated from [`scene_entries!`](crate::scene_entries).
        #[repr(C)]
        #[derive(::abi_stable::StableAbi)]
        #[sabi(kind(Prefix(prefix_ref = $prefix)))]
        pub struct $module {
            $($acc)*
        }
    };
    (@munch [$kind:ident $module:ident $prefix:ident] [$($acc:tt)*]) => {
        #[doc = concat!("The root module of a plugin of kind `", stringify!($kind),
                        "`, generated from its declaration in [`crate::entries`].")]
        #[repr(C)]
        #[derive(::abi_stable::StableAbi)]
        #[sabi(kind(Prefix(prefix_ref = $prefix)))]
        pub struct $module {
            /// Common metadata.
            pub meta: $crate::ModuleMeta,
            /// The paper's "create": from parameters (JSON text); null on
            /// error, with the error in the sink.
            pub create: unsafe extern "C" fn(
                params: $crate::Span<u8>,
                env: *const $crate::CreateEnv,
                sink: $crate::ErrSink,
            ) -> *mut ::std::ffi::c_void,
            /// Destroy what `create` (or a `ctor` entry) made.
            pub destroy: unsafe extern "C" fn(this: *mut ::std::ffi::c_void),
            $($acc)*
        }
    };
}
