mod a;
mod d;
